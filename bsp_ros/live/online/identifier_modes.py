"""`bsp_identifier`'s two modes behind one Protocol: the sliding window (windowed) and the per-sample filter held to
its checked window (recursive). :func:`mode_for` is the one place that picks a mode."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import Finding
from bsp_ros.core.methods import LiveMode, Method
from bsp_ros.core.pipeline import recursive_estimate
from bsp_ros.live.online.identifier_settings import IdentifierSettings
from bsp_ros.live.online.recursive_check import WindowCheck
from bsp_ros.live.online.recursive_feed import RecursiveFeed
from bsp_ros.live.online.windowed import WindowConfig, WindowedIdentifier, WindowEstimate
from msg_adapters.joint_state import JointStateSample

__all__ = [
    "EstimateJob",
    "IdentifierMode",
    "ModeEstimate",
    "Orientation",
    "RecursiveMode",
    "WindowedMode",
    "mode_for",
]


@dataclass(frozen=True)
class ModeEstimate:
    """One update's estimate (with its ``mode``), the stamp it goes out with (ns), and whether the passive moments go
    out with it (``bsp/passive_moments``; the recursive mode's go per sample)."""

    estimate: Estimate
    stamp_ns: int
    with_passive: bool


# An estimate to compute: the caller times it, and a failure becomes an invalid estimate (``LiveIdentifier``).
EstimateJob = Callable[[], ModeEstimate]
# The wrench sensor's frame and its rotation (3, 3) ``world <- sensor`` at the newest wrench, or None before one.
Orientation = tuple[str, np.ndarray] | None

# The window's model checks: a window of its own this many seconds stale is invalid (the node judges staleness).
_WINDOW_STALE_S = 60.0


def _invalid(mode: LiveMode, method: Method, reason: Finding, now_ns: int, with_passive: bool) -> ModeEstimate:
    """An invalid estimate stamped ``now_ns`` saying why (an input stale or waiting)."""
    return ModeEstimate(Estimate.invalid(method, reason).with_mode(mode), now_ns, with_passive)


class IdentifierMode(Protocol):
    """What an identifier mode does with the samples the node takes, and what it publishes each update.

    Both modes fill ``window`` (a :class:`WindowedIdentifier`) with the unfiltered angles and every wrench: the
    windowed mode's estimate, the recursive mode's model checks.
    """

    name: LiveMode  # the estimates' ``mode``
    takes_joint_states: bool  # the causally filtered joint states (arm/joint_states) feed it
    raw_angles_count: str  # the diagnostics counter of the unfiltered angles it accepts
    window: WindowedIdentifier

    def add_wrench(
        self, stamp_ns: int, t_ns: int, wrench_yzx: np.ndarray, lengths_m: np.ndarray | None
    ) -> tuple[bool, JointStateSample | None]:
        """A wrench ``[F_y, F_z, M_x]`` in world measured at ``t_ns`` (stamped ``stamp_ns``): whether it was taken,
        and the passive moments to publish now (None: nothing per sample)."""
        ...

    def add_joint_state(
        self, t_ns: int, q_rad: np.ndarray, velocity_rad_s: np.ndarray, lengths_m: np.ndarray | None
    ) -> bool:
        """Causally filtered joint angles and direction velocities (``takes_joint_states``); False if refused."""
        ...

    def update(
        self, now_ns: int, reason: Finding | None, orientation: Orientation, lengths_m: np.ndarray | None
    ) -> ModeEstimate | EstimateJob:
        """This update's estimate: a quick verdict at once, or the job that computes it.

        Parameters
        ----------
        now_ns : the node's clock (the stamp of an estimate without samples).
        reason : why no estimate can be made now (an input stale or waiting), or None.
        orientation : the wrench sensor's frame and rotation, for the sensor zero's share of the std.
        lengths_m : the newest segment lengths (set whenever ``reason`` is None).
        """
        ...

    def reset(self) -> None:
        """Forget every sample (samples rotated or placed another way must not mix with new ones)."""
        ...

    def counters(self) -> dict[str, int]:
        """The mode's own counters for /diagnostics."""
        ...


class WindowedMode:
    """The newest ``window_s`` of samples identified each update, as `bsp identify` would identify them (the model
    checks every ``WindowConfig.elastic_check_every`` updates, refits of what they chose in between)."""

    name = LiveMode.WINDOWED
    takes_joint_states = False
    raw_angles_count = "joint_states"

    def __init__(self, settings: IdentifierSettings) -> None:
        self.method = settings.options.method
        self.window = WindowedIdentifier(
            settings.n_segments, WindowConfig(settings.window_s, _WINDOW_STALE_S, settings.options)
        )

    def add_wrench(
        self, stamp_ns: int, t_ns: int, wrench_yzx: np.ndarray, lengths_m: np.ndarray | None
    ) -> tuple[bool, JointStateSample | None]:
        return self.window.add_wrench(t_ns, wrench_yzx), None

    def add_joint_state(
        self, t_ns: int, q_rad: np.ndarray, velocity_rad_s: np.ndarray, lengths_m: np.ndarray | None
    ) -> bool:
        return False  # not taken (takes_joint_states is False): the window filters the unfiltered angles itself

    def update(
        self, now_ns: int, reason: Finding | None, orientation: Orientation, lengths_m: np.ndarray | None
    ) -> ModeEstimate | EstimateJob:
        """The newest window's estimate, published as soon as it is computed (stamped with the window's newest
        wrench); a quick verdict (stale, waiting) instead when there is no window to identify."""
        if reason is not None:
            return _invalid(self.name, self.method, reason, now_ns, with_passive=True)
        # The sensor's orientation rides with the window: the zero's uncertainty (the tare's, or zero_sd_n's without
        # one) joins the std, as `bsp identify` adds it.
        window = self.window.snapshot(orientation=orientation)
        if isinstance(window, WindowEstimate):
            stamp_ns = window.last_wrench_t_ns or now_ns
            return ModeEstimate(window.estimate.with_mode(self.name), stamp_ns, with_passive=True)
        estimator = self.window.estimator

        def job() -> ModeEstimate:
            estimate = estimator.estimate_window(window)
            stamp_ns = estimate.last_wrench_t_ns or 0
            return ModeEstimate(estimate.estimate.with_mode(self.name), stamp_ns, with_passive=True)

        return job

    def reset(self) -> None:
        self.window.reset()

    def counters(self) -> dict[str, int]:
        return {}


class RecursiveMode:
    """The recursive filter, one wrench at a time (its passive moments published per sample), held each update to
    its window's checked estimate (the window identified with every model check every ``CHECK_EVERY`` updates)."""

    name = LiveMode.RECURSIVE
    takes_joint_states = True
    raw_angles_count = "raw_angles"  # its joint states are the causal ones; these only fill its checks' window

    def __init__(self, settings: IdentifierSettings) -> None:
        self.options = settings.options
        config = WindowConfig(settings.window_s, _WINDOW_STALE_S, settings.options, elastic_check_every=1)
        self.window = WindowedIdentifier(settings.n_segments, config)
        self.window_check = WindowCheck(self.window)
        self.feed = RecursiveFeed(settings.n_segments, settings.options.passive, settings.options.subject)

    def add_wrench(
        self, stamp_ns: int, t_ns: int, wrench_yzx: np.ndarray, lengths_m: np.ndarray | None
    ) -> tuple[bool, JointStateSample | None]:
        accepted, coulomb_nm = self.feed.add_wrench(t_ns, wrench_yzx, lengths_m)
        joints = self.feed.passive_joints
        passive = None
        if coulomb_nm is not None and len(joints) == coulomb_nm.size:
            passive = JointStateSample(stamp_ns, "", joints, np.zeros(0), np.zeros(0), coulomb_nm)
        self.window.add_wrench(t_ns, wrench_yzx)  # for the checks (after the filter: its moments go out first)
        return accepted, passive

    def add_joint_state(
        self, t_ns: int, q_rad: np.ndarray, velocity_rad_s: np.ndarray, lengths_m: np.ndarray | None
    ) -> bool:
        return self.feed.add_joint_state(t_ns, q_rad, velocity_rad_s, lengths_m)

    def update(
        self, now_ns: int, reason: Finding | None, orientation: Orientation, lengths_m: np.ndarray | None
    ) -> ModeEstimate | EstimateJob:
        """The filter's state, held to its window's checked estimate, fused with the prior (~2 ms; every 10 s the
        window's model checks, 20-40 ms)."""
        if reason is not None:
            method = self.options.method
            return lambda: _invalid(self.name, method, reason, now_ns, with_passive=False)
        assert lengths_m is not None  # no reason to wait: the lengths came
        lengths, stamp = lengths_m.copy(), self.feed.guard.last_t_ns or 0
        robot = self.window.contact_from_robot

        def job() -> ModeEstimate:
            self.window_check.tick(orientation)  # the window's model checks, when due (timed with the update)
            result = self.window_check.checked(self.feed.identifier.result())
            estimate = recursive_estimate(result, lengths, self.options, robot).with_mode(self.name)
            return ModeEstimate(estimate, stamp, with_passive=False)

        return job

    def reset(self) -> None:
        self.window.reset()
        self.feed.reset()

    def counters(self) -> dict[str, int]:
        return {"wrench_spikes": self.feed.spike_gate.spikes}  # taken, kept out of the filter


_MODES: dict[LiveMode, Callable[[IdentifierSettings], IdentifierMode]] = {
    WindowedMode.name: WindowedMode,
    RecursiveMode.name: RecursiveMode,
}


def mode_for(settings: IdentifierSettings) -> IdentifierMode:
    """The mode ``settings.mode`` names (the one place a mode is chosen)."""
    return _MODES[settings.mode](settings)
