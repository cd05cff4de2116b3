"""The live window's estimator: a window's samples in, its estimate out, with the model checks' schedule."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from bsp_ros.core.estimate import estimate_from_fit
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import FindingCode, note
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.held import HeldModel
from bsp_ros.core.identification.rate import block_means, identification_rate_hz
from bsp_ros.core.identification.sensitivity import TareShare, account_for_tare
from bsp_ros.core.identification.timing import parameter_timing_block
from bsp_ros.core.joint_angles import KinematicsConfig, MarkerKinematics, kinematics_from_angles, resample_with_motion
from bsp_ros.core.model import contact_torques_nm
from bsp_ros.core.pipeline import fused, identify_data, refit_options
from bsp_ros.errors import BspError
from bsp_ros.live.online.finding_hold import FindingHold
from bsp_ros.live.online.window_samples import WindowConfig, WindowEstimate, WindowSamples

# A zero-phase filtered angle this far behind the newest is settled: what the backward pass brings from the end has
# decayed to e^-11 (the slowest filter, the direction velocity's at 0.5 Hz, decays with ~0.45 s). The updates
# between checks keep the settled kinematics and filter only the newest seconds, from this much before the settled
# end, where the forward pass has decayed as much from its start.
SETTLED_S = 5.0
TAIL_LEAD_S = 5.0


@dataclass(frozen=True)
class WindowSettings:
    """What a window's samples are prepared with, held between model checks: the segment lengths (n,) m (the
    window's median), the kinematics filter settings (cutoffs raised to the motion's band), the angle grid
    (origin and step, ns) and the direction velocity's noise (n,) rad/s (the dead band at reversals)."""

    lengths_m: np.ndarray
    kinematics: KinematicsConfig
    grid: tuple[int, int]
    direction_noise_rad_s: np.ndarray


# The fields of MarkerKinematics with one row per grid point.
_PER_POINT = ("t_ns", "q_rad", "direction_velocity_rad_s", "velocity_rad_s", "acceleration_rad_s2")


def _grid_points(*parts: tuple[MarkerKinematics, slice]) -> MarkerKinematics:
    """The grid points ``keep`` (a range of them) of each ``(kinematics, keep)`` part, joined in order; the other
    fields (settings, noise, notes) are the last part's."""

    def joined(name: str) -> np.ndarray | None:
        values = [getattr(kinematics, name) for kinematics, _ in parts]
        if any(v is None for v in values):
            return None
        return np.concatenate([v[keep] for v, (_, keep) in zip(values, parts, strict=True)])

    points: dict[str, Any] = {name: joined(name) for name in _PER_POINT}
    return dataclasses.replace(parts[-1][0], **points)


def _from(t_ns: np.ndarray, first_ns: int, inclusive: bool = True) -> slice:
    """The grid points at or after (``inclusive``) or after ``first_ns``: the grid's stamps increase, so a range
    (a view of each field until the join copies it, where a boolean mask gathered a copy of each first)."""
    return slice(int(np.searchsorted(t_ns, first_ns, "left" if inclusive else "right")), None)


class WindowEstimator:
    """Identifies copies of a window (:class:`WindowSamples`), one thread at a time.

    It keeps what the model checks chose and when they run next, and the settled part of the last window's
    kinematics; a copy from a new buffer epoch (the buffers were cleared since) starts the checks again.
    """

    def __init__(self, n_segments: int, config: WindowConfig | None = None) -> None:
        self.n = n_segments
        self.config = config or WindowConfig()
        self._since_check = 0
        self._held: HeldModel | None = None
        self._hold = FindingHold()  # what a check found holds through one check that misses it
        # What the window the last check identified was prepared with (lengths, cutoffs, grid, noise).
        self._held_settings: WindowSettings | None = None
        # The last update's kinematics older than SETTLED_S before its newest angle (on the held grid).
        self._settled: MarkerKinematics | None = None
        self._epoch = 0

    def restart_checks(self) -> None:
        """Forget what the model checks chose: the next :meth:`estimate_window` runs them again."""
        self._since_check = 0
        self._held = None
        self._held_settings = None
        self._settled = None
        self._hold.reset()

    def _invalid(self, detail: str, last_wrench_t_ns: int) -> WindowEstimate:
        estimate = Estimate.invalid(self.config.options.method, note(FindingCode.INPUT_UNUSABLE, detail))
        return WindowEstimate(estimate, False, last_wrench_t_ns)

    def _window_data(
        self, window: WindowSamples, held: WindowSettings | None = None
    ) -> tuple[IdentificationData | str, WindowSettings]:
        """The identification data of a window (its samples' stamps: ``t_ns``), or why there are none, and the
        settings it was prepared with: ``held`` (a check's), else the window's own."""
        t_w, wrench, _ = block_means(window.wrench_t_ns, window.wrench_yzx, self.config.max_rate_hz)
        t_a, rows = window.angle_t_ns, window.angle_rows
        if held is None:
            lengths = np.median(rows[:, self.n :], axis=0)
            kinematics = kinematics_from_angles(
                t_a, rows[:, : self.n], lengths, self.config.options.kinematics, angle_filter=True
            )
            settings = WindowSettings(
                kinematics.lengths_m,
                kinematics.config or self.config.options.kinematics,
                (int(kinematics.t_ns[0]), int(kinematics.t_ns[1] - kinematics.t_ns[0])),
                kinematics.direction_velocity_noise_rad_s,
            )
        else:
            kinematics, settings = self._held_kinematics(t_a, rows[:, : self.n], held), held
        settled_end = int(np.searchsorted(kinematics.t_ns, int(t_a[-1]) - int(SETTLED_S * 1e9), "right"))
        self._settled = _grid_points((kinematics, slice(0, settled_end)))
        # As offline: the newest half second has no settled derivative yet and is left out (resample_with_motion).
        q, velocity, qd, qdd, valid = resample_with_motion(kinematics, t_w)
        if valid.sum() < 2:
            return "no wrench sample in the window has joint angles", settings
        tau = contact_torques_nm(q[valid], settings.lengths_m, wrench[valid])
        data = IdentificationData(
            t_ns=t_w[valid],
            q_rad=q[valid],
            velocity_rad_s=velocity[valid],
            tau_nm=tau,
            lengths_m=settings.lengths_m,
            lengths_std_m=np.zeros(self.n),
            velocity_noise_rad_s=settings.direction_noise_rad_s,
            n_wrench_samples=int(t_w.size),
            warnings=[],
            qd_rad_s=qd[valid],
            qdd_rad_s2=qdd[valid],
            contact_from_robot=window.contact_from_robot,
            emg=window.emg,  # its active stretches left out as offline (leave_out_activity, refit_held)
        )
        return data, settings

    def _held_kinematics(self, t_ns: np.ndarray, q_rad: np.ndarray, held: WindowSettings) -> MarkerKinematics:
        """The window's kinematics on ``held``'s settings: the settled part of the last update's and the newest
        seconds filtered anew on the same grid (all of the window when nothing is settled yet)."""
        settled = self._settled

        def filtered(first: int) -> MarkerKinematics:
            return kinematics_from_angles(
                t_ns[first:],
                q_rad[first:],
                held.lengths_m,
                held.kinematics,
                angle_filter=True,
                adapt_to_motion=False,
                grid=held.grid,
            )

        origin, step = held.grid
        if (
            settled is None
            or settled.t_ns.size < 2
            or (int(settled.t_ns[0]) - origin) % step  # kept from a window on another grid
            or settled.t_ns[-1] - TAIL_LEAD_S * 1e9 < t_ns[0]
        ):
            return filtered(0)
        tail = filtered(int(np.searchsorted(t_ns, settled.t_ns[-1] - int(TAIL_LEAD_S * 1e9))))
        return _grid_points(
            (settled, _from(settled.t_ns, int(t_ns[0]))),
            (tail, _from(tail.t_ns, int(settled.t_ns[-1]), inclusive=False)),
        )

    def _due(self) -> bool:
        """Whether this update runs the model checks: the first, every ``elastic_check_every``-th, and every update
        while the last one's samples could not support an estimate (poor excitation, a misfit: nothing to hold). A
        model the checks found lacking holds its verdict until the next check."""
        every = self.config.elastic_check_every
        return self._held is None or self._since_check >= every or bool(self._held.data_problems)

    def estimate_window(self, window: WindowSamples) -> WindowEstimate:
        """Identify a window copied by :meth:`snapshot` (one thread at a time).

        Every ``elastic_check_every``-th call (the first included) identifies with the model checks (drift,
        Stribeck, elastic: ~30 ms for 30 s at 1 kHz); the calls in between refit the model they chose, with its
        verdict (:func:`bsp_ros.core.identification.joint.refit.refit_held`: one fit), on the segment lengths and
        filter cutoffs of the checked window.
        """
        last_wrench = int(window.wrench_t_ns[-1])
        if window.epoch != self._epoch:  # samples from before a reset: what the checks chose does not hold
            self.restart_checks()
            self._epoch = window.epoch
        try:
            check = self._due()
            held_settings = None if check else self._held_settings
            data, settings = self._window_data(window, held_settings)
            if isinstance(data, str):
                return self._invalid(data, last_wrench)
            if check:
                result = self._hold.checked(
                    identify_data(data, self.config.options, check_elastic=True, check_drift=True)
                )
                self._held, self._held_settings, self._since_check = result.held, settings, 1
            else:
                result = identify_data(data, self.config.options, held=self._held)
                self._since_check += 1
            tare_share: TareShare | None = None
            if window.rotation_world_from_sensor is not None:
                # The sensor zero's share of the std (the tare's, or the assumed zero's), from the estimate's own
                # response to a torque change (no refits).
                options = self.config.options
                refit = refit_options(result, options)
                result, tare_share = account_for_tare(
                    result,
                    data,
                    window.rotation_world_from_sensor,
                    window.wrench_frame_id,
                    options.tare,
                    lambda d: identify_data(d, refit, check_elastic=False),
                    (options.zero_sd_n, options.zero_sd_nm),
                )
        except BspError as error:
            return self._invalid(str(error), last_wrench)
        posterior, result = fused(result, data, self.config.options.subject) if result.valid else (None, result)
        info = {
            "start_time_ns": int(data.t_ns[0]),
            "end_time_ns": int(data.t_ns[-1]),
            "window_s": self.config.window_s,
            "identification_rate_hz": identification_rate_hz(data.t_ns),
            "refused_samples": window.refused,
            "clock_jumps": window.clock_jumps,
            "config": self.config.options.config(),
        }
        estimate = estimate_from_fit(
            result,
            data,
            posterior=posterior,
            subject=self.config.options.subject,
            placement_sd_m=self.config.options.placement_sd_used_m(result, data),
            session=info,
        )
        # The node shifts the wrench stamps by the delay the cell states: its timing, then the sensor zero's share.
        quality = estimate.quality.with_timing(parameter_timing_block(self.config.options.wrench_delay_s))
        if tare_share is not None:
            quality = tare_share.applied_to(quality)
        return WindowEstimate(estimate.with_quality(quality), result.valid, last_wrench)
