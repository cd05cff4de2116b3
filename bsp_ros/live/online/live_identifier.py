"""What `bsp_identifier` does with its inputs whatever its mode: the segment lengths, the wrench as the identifiers
take it, which input is stale, the counters and update times of /diagnostics; the rest is its mode's
(:mod:`bsp_ros.live.online.identifier_modes`)."""

from __future__ import annotations

import time
import traceback
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Generic, TypeVar

import numpy as np

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.live.online.identifier_modes import IdentifierMode, ModeEstimate, Orientation, mode_for
from bsp_ros.live.online.identifier_settings import IdentifierSettings
from bsp_ros.live.online.receipt_stamps import ReceiptStamps
from bsp_ros.live.online.wrench_input import WrenchInput
from msg_adapters.joint_state import JointStateSample
from msg_adapters.wrench import WrenchSample

__all__ = ["LiveIdentifier"]

Outputs = TypeVar("Outputs")


class LiveIdentifier(Generic[Outputs]):
    """Samples in (adapted from their messages by the node), one estimate per update out.

    Samples that are non-finite, out of order or duplicated never enter an estimate (the mode's guards refuse and
    count them); an estimate is invalid while an input is waiting or stale (nothing received for ``stale_s``).

    Parameters
    ----------
    settings : the node's settings (the mode, the tare, the wrench delay, ``stale_s``, ``update_hz``).
    serialize : what an update's estimate becomes (the node's: its messages, ``estimate_jobs.outputs_from_estimate``);
        a computed estimate is timed with it.
    log_error : where an estimate that failed unexpectedly logs its traceback (it is published invalid).
    frame_findings : what holds now of the wrench frame's rotation (the node's
        :meth:`bsp_ros.live.online.frame_notices.FrameNotices.findings`): added to every estimate.
    """

    def __init__(
        self,
        settings: IdentifierSettings,
        serialize: Callable[[ModeEstimate], Outputs],
        log_error: Callable[[str], None],
        frame_findings: Callable[[], Sequence[Finding]] = tuple,
    ) -> None:
        self.n = settings.n_segments
        self.stale_s = settings.stale_s
        self.method = settings.options.method
        self.mode: IdentifierMode = mode_for(settings)
        # The tare's load off and the wrench delay compensated (0 when unset: live cannot estimate it).
        self.wrench_input = WrenchInput(settings.options.tare, settings.live_wrench_delay_s)
        self.orientation: Orientation = None  # the latest wrench's frame and rotation
        # EMG envelopes carry no stamp: their receipt, on the wrench stamps' clock.
        self.emg_stamps = ReceiptStamps()
        self.lengths: np.ndarray | None = None
        # Unfiltered angles that came before the first segment lengths (a topic of their own, which can match
        # later or be taken after them); they join the window when the lengths arrive.
        self.early_angles: deque[tuple[int, np.ndarray]] = deque(maxlen=4000)
        self.last_receive: dict[str, int | None] = {"wrench": None, "joint_states": None}
        self.counts = {"wrench": 0, "joint_states": 0, "refused": 0}
        # The last ~10 s of updates: compute time and the thread's own CPU time in it, s. Below the compute time,
        # an update waited for a core (the other nodes, Fast DDS's threads).
        self.update_s: deque[tuple[float, float]] = deque(maxlen=int(10 * settings.update_hz) + 1)
        self._serialize = serialize
        self._log_error = log_error
        self._frame_findings = frame_findings

    def _count(self, key: str) -> None:
        self.counts[key] = self.counts.get(key, 0) + 1

    # -- inputs ---------------------------------------------------------------------------------------
    def received(self, what: str, now_ns: int) -> None:
        """A message of input ``what`` (``wrench``, ``joint_states``) came at ``now_ns`` (staleness)."""
        self.last_receive[what] = now_ns

    def wrench_received(self, stamp_ns: int, now_ns: int) -> None:
        """A wrench stamped ``stamp_ns`` came at ``now_ns`` (node clock): staleness, and the offset that stamps the EMG
        envelopes on the wrench's clock."""
        self.received("wrench", now_ns)
        self.emg_stamps.wrench(stamp_ns, now_ns)

    def add_emg(self, channels: tuple[str, ...], values: np.ndarray, now_ns: int) -> None:
        """One EMG envelope message (its channels' names and values (C,)) received at ``now_ns`` (node clock),
        stamped at its receipt on the wrench's clock (:class:`ReceiptStamps`; before any wrench it is dropped and
        counted) into the mode's window: the windowed mode's estimate, the recursive mode's window checks, leave
        the stretches it shows active out as `bsp identify` does."""
        t_ns = self.emg_stamps.stamp(now_ns)
        if t_ns is None:
            self._count("emg_before_wrench")
            return
        self._count("emg" if self.mode.window.add_emg(t_ns, channels, values) else "refused")

    def add_lengths(self, lengths_m: np.ndarray) -> None:
        """Segment lengths (m); the angles that waited for the first ones join the window."""
        if lengths_m.size == self.n and np.isfinite(lengths_m).all() and (lengths_m > 0).all():
            self.lengths = lengths_m
            while self.early_angles:
                self._add_raw_angles(*self.early_angles.popleft())

    def add_raw_angles(self, t_ns: int, q_rad: np.ndarray, now_ns: int) -> None:
        """Unfiltered joint angles: the window filters them with zero phase, like `bsp identify`."""
        self.received("joint_states", now_ns)
        if q_rad.size != self.n:
            return
        if self.lengths is None:
            self.early_angles.append((t_ns, q_rad))
            return
        self._add_raw_angles(t_ns, q_rad)

    def _add_raw_angles(self, t_ns: int, q_rad: np.ndarray) -> None:
        assert self.lengths is not None
        accepted = self.mode.window.add_joint_state(t_ns, q_rad, self.lengths)
        self._count(self.mode.raw_angles_count if accepted else "refused")

    def add_joint_state(self, sample: JointStateSample, now_ns: int) -> None:
        """Causally filtered joint angles and direction velocities, for a mode that takes them."""
        if not self.mode.takes_joint_states:
            return
        self.received("joint_states", now_ns)
        accepted = self.mode.add_joint_state(sample.t_ns, sample.position, sample.velocity, self.lengths)
        self._count("joint_states" if accepted else "refused")

    def add_wrench(self, sample: WrenchSample, rotation: np.ndarray | None) -> JointStateSample | None:
        """A wrench with its sensor's rotation at its stamp (None: still waiting for a first transform); returns the
        passive moments the mode publishes per sample, if any."""
        if rotation is None:
            self._count("waiting_for_tf")
            return None
        world = self.wrench_input.world(sample, rotation)
        if world is None:
            self._count("tare_frame_mismatch")
            return None
        self.orientation = (sample.frame_id, rotation)
        t_ns, wrench_yzx = world
        accepted, passive = self.mode.add_wrench(sample.t_ns, t_ns, wrench_yzx, self.lengths)
        self._count("wrench" if accepted else "refused")
        return passive

    def set_contact_from_robot(self, robot: bool) -> bool:
        """Where the angles' contact point comes from (the robot's handle pose: its registration sd in the
        estimate; a skin marker: the marker placement sd); True if it changed and the estimate restarted."""
        if robot == self.mode.window.contact_from_robot:
            return False
        self.reset()  # the hand's segment length changes with the source: samples of both must not mix
        self.mode.window.contact_from_robot = robot
        return True

    def reset(self) -> None:
        """Forget every sample (the wrench's rotation or the contact point changed)."""
        self.mode.reset()

    # -- outputs --------------------------------------------------------------------------------------
    def stale_reason(self, now_ns: int) -> Finding | None:
        """Why no estimate can be made now (an input never came or fell silent for ``stale_s``), or None."""
        for name, last in self.last_receive.items():
            if last is None:
                return Finding(code=FindingCode.INPUT_WAITING, values={"what": name})
            if now_ns - last > self.stale_s * 1e9:
                return Finding(code=FindingCode.INPUT_STALE, values={"what": name, "silent_s": (now_ns - last) / 1e9})
        if self.lengths is None:
            return Finding(code=FindingCode.INPUT_WAITING, values={"what": "segment lengths"})
        return None

    def update(self, now_ns: int) -> Outputs:
        """This update's estimate (invalid if an input is waiting or stale); a computed one is timed, and one that
        fails unexpectedly is published invalid with its traceback logged."""
        update = self.mode.update(now_ns, self.stale_reason(now_ns), self.orientation, self.lengths)
        if isinstance(update, ModeEstimate):  # a quick verdict
            return self._serialize(self._with_frame_findings(update))
        started, started_cpu = time.perf_counter(), time.thread_time()
        try:
            outputs = self._serialize(self._with_frame_findings(update()))
        except Exception as exc:
            self._log_error(f"estimate failed: {traceback.format_exc()}")
            finding = Finding(code=FindingCode.INTERNAL_ERROR, values={"error": repr(exc)})
            estimate = Estimate.invalid(self.method, finding).with_mode(self.mode.name)
            outputs = self._serialize(ModeEstimate(estimate, now_ns, with_passive=False))
        self.update_s.append((time.perf_counter() - started, time.thread_time() - started_cpu))
        return outputs

    def _with_frame_findings(self, estimate: ModeEstimate) -> ModeEstimate:
        """``estimate`` with the wrench frame's findings in its quality."""
        findings = self._frame_findings()
        if not findings:
            return estimate
        return replace(estimate, estimate=estimate.estimate.with_findings(*findings))

    def counters(self) -> dict[str, int]:
        """The samples taken, refused and waiting, and the mode's own counters."""
        return {**self.counts, **self.mode.counters()}

    def update_times(self) -> dict[str, str]:
        """How long an update takes (ms; near the period, the node cannot keep up), once one was computed."""
        if not self.update_s:
            return {}
        wall_cpu_ms = 1e3 * np.array(self.update_s)
        mean, top = wall_cpu_ms.mean(axis=0), wall_cpu_ms.max(axis=0)
        return {
            "update_ms_mean": f"{mean[0]:.1f}",
            "update_ms_max": f"{top[0]:.1f}",
            "update_cpu_ms_mean": f"{mean[1]:.1f}",
            "update_cpu_ms_max": f"{top[1]:.1f}",
        }
