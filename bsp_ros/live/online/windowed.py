"""Sliding-window identification for live use: the batch estimator over the last `window_s` seconds."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.live.online.buffer import TimedBuffer
from bsp_ros.live.online.emg_buffer import EmgBuffer
from bsp_ros.live.online.guard import StreamGuard, absurd_wrench_yzx
from bsp_ros.live.online.window_estimator import WindowEstimator
from bsp_ros.live.online.window_samples import WindowConfig, WindowEstimate, WindowSamples

__all__ = ["WindowConfig", "WindowEstimate", "WindowEstimator", "WindowSamples", "WindowedIdentifier"]

# A window's EMG starts this long before its first wrench: a burst that ended just before the window reaches into it
# by the rule's widening after its end (0.3 s) and its mean over 100 ms.
EMG_LEAD_NS = 1_000_000_000


class WindowedIdentifier:
    """Wrench and unfiltered joint-angle samples (and EMG envelopes, where a cell sends them) in, an estimate of the
    last ``window_s`` seconds out.

    The angles are filtered here with zero phase over the window, exactly as `bsp identify` does offline.

    Samples that are non-finite, out of order or duplicated, and wrenches beyond any arm's force (a glitch `bsp
    identify` removes too), are refused and counted; a backwards clock jump clears both buffers, so no estimate
    mixes samples from either side of it.

    The buffers and :meth:`snapshot` belong to the thread that receives the samples; :meth:`estimate_window`
    (``estimator``, :class:`WindowEstimator`) may run on another, one thread at a time.
    """

    def __init__(
        self, n_segments: int, config: WindowConfig | None = None, estimator: WindowEstimator | None = None
    ) -> None:
        self.n = n_segments
        self.config = config or WindowConfig()
        self.estimator = estimator or WindowEstimator(n_segments, self.config)
        horizon_ns = int((self.config.window_s + 5.0) * 1e9)
        self.wrench = TimedBuffer(3, horizon_ns)
        self.angles = TimedBuffer(2 * n_segments, horizon_ns)
        self.emg = EmgBuffer(horizon_ns)
        self.wrench_guard = StreamGuard("wrench", absurd=absurd_wrench_yzx)
        self.angle_guard = StreamGuard("joint_states")
        # Set by the node from `arm/contact_point`: the contact point's placement sd in the estimate follows it.
        self.contact_from_robot = False
        self.epoch = 0  # the buffers' clears: a window copied after one starts the model checks again

    def add_wrench(self, t_ns: int, wrench_yzx: np.ndarray) -> bool:
        """Add ``[F_y, F_z, M_x]`` in ``world`` at ``t_ns``; False if refused."""
        verdict = self.wrench_guard.check(t_ns, wrench_yzx)
        if verdict in ("jump", "gap"):
            self.reset()
            self.wrench_guard.last_t_ns = t_ns
        if verdict == "refused":
            return False
        self.wrench.append(t_ns, wrench_yzx)
        return True

    def add_joint_state(self, t_ns: int, q_rad: np.ndarray, lengths_m: np.ndarray) -> bool:
        """Add joint angles (rad) and segment lengths (m) at ``t_ns``; False if refused."""
        row = np.concatenate((q_rad, lengths_m))
        verdict = self.angle_guard.check(t_ns, row)
        if verdict in ("jump", "gap"):
            self.reset()
            self.angle_guard.last_t_ns = t_ns
        if verdict == "refused":
            return False
        self.angles.append(t_ns, row)
        return True

    def add_emg(self, t_ns: int, channels: tuple[str, ...], values: np.ndarray) -> bool:
        """Add one message's EMG envelopes ``values`` (C,) of ``channels`` at ``t_ns`` (its receipt on the stamps'
        clock); False if refused (:class:`EmgBuffer`)."""
        return self.emg.add(t_ns, channels, values)

    def reset(self) -> None:
        """Forget every sample (a new session or a clock jump); the next update runs the model checks."""
        self.wrench.clear()
        self.angles.clear()
        self.emg.clear()
        self.epoch += 1

    def restart_checks(self) -> None:
        """Forget what the model checks chose: the next :meth:`estimate_window` runs them again."""
        self.estimator.restart_checks()

    def _invalid(self, finding: Finding) -> WindowEstimate:
        return WindowEstimate(Estimate.invalid(self.config.options.method, finding), False, self.wrench.last_t_ns)

    def estimate(self, now_ns: int | None = None, orientation: tuple[str, np.ndarray] | None = None) -> WindowEstimate:
        """Identify over the newest window: :meth:`snapshot` then :meth:`estimate_window`.

        Parameters
        ----------
        now_ns : the caller's clock, in the stamps' time base; None judges staleness between the inputs only.
        orientation : as for :meth:`snapshot`.
        """
        window = self.snapshot(now_ns, orientation)
        return window if isinstance(window, WindowEstimate) else self.estimate_window(window)

    def snapshot(
        self, now_ns: int | None = None, orientation: tuple[str, np.ndarray] | None = None
    ) -> WindowSamples | WindowEstimate:
        """Copy the newest window's samples (cheap), or an invalid estimate when an input is missing or stale.

        The copy can be identified on another thread (:meth:`estimate_window`) while samples keep arriving.

        Parameters
        ----------
        now_ns : the caller's clock, in the stamps' time base; None judges staleness between the inputs only.
        orientation : the wrench sensor's frame and rotation (3, 3) ``world <- sensor``, when known: the window
            carries them, and the sensor zero's uncertainty (a tare's, or the assumed ``zero_sd_n``) joins its std.
        """
        last_wrench, last_angle = self.wrench.last_t_ns, self.angles.last_t_ns
        if last_wrench is None or last_angle is None:
            return self._invalid(Finding(code=FindingCode.INPUT_WAITING, values={"what": "wrench and joint states"}))
        stale_ns = self.config.stale_s * 1e9
        newest = max(last_wrench, last_angle) if now_ns is None else now_ns
        for name, last in (("wrench", last_wrench), ("joint states", last_angle)):
            if newest - last > stale_ns:
                values = {"what": name, "silent_s": (newest - last) / 1e9, "newest": True}
                return self._invalid(Finding(code=FindingCode.INPUT_STALE, values=values))
        start = last_wrench - int(self.config.window_s * 1e9)
        refused = {
            **{f"wrench_{k}": v for k, v in self.wrench_guard.refused.items()},
            **{f"joint_states_{k}": v for k, v in self.angle_guard.refused.items()},
        }
        frame_id, rotation = orientation if orientation is not None else ("", None)
        wrench_t_ns, wrench_yzx = self.wrench.since(start)
        angle_t_ns, angle_rows = self.angles.since(start - int(2e9))
        return WindowSamples(
            wrench_t_ns=wrench_t_ns,
            wrench_yzx=wrench_yzx,
            angle_t_ns=angle_t_ns,
            angle_rows=angle_rows,
            refused=refused,
            clock_jumps=self.wrench_guard.clock_jumps + self.angle_guard.clock_jumps,
            rotation_world_from_sensor=rotation,
            wrench_frame_id=frame_id,
            contact_from_robot=self.contact_from_robot,
            epoch=self.epoch,
            emg=self.emg.series(start - EMG_LEAD_NS),
        )

    def estimate_window(self, window: WindowSamples) -> WindowEstimate:
        """Identify a window copied by :meth:`snapshot` (:meth:`WindowEstimator.estimate_window`)."""
        return self.estimator.estimate_window(window)
