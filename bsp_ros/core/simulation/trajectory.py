"""Joint motions the simulated robot imposes: slow sines (TrajectorySpec) or any JointTrajectory."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from bsp_ros.core.normalised import normalising
from bsp_ros.core.simulation.checks import check_n_segments, float_tuple
from bsp_ros.errors import InputError
from bsp_ros.validation import check_positive

# Step of the central difference that gives the acceleration of a trajectory without an analytic one, s.
_ACCELERATION_STEP_S = 1e-4


@normalising
@dataclass(frozen=True)
class TrajectorySpec:
    """Slow sinusoidal joint motion ``q_j(t) = center_j + amp_j sin(2 pi t / period_j + phase_j)``.

    Attributes
    ----------
    center_deg : (n,) operating point, deg (q1 absolute from +y, q2 and q3 relative).
    amplitude_deg : (n,) amplitude >= 0, deg (0 holds the joint still: qdot = 0 exactly).
    period_s : (n,) period > 0, s.
    phase_rad : (n,) phase at t = 0 (the session start), rad.
    """

    center_deg: tuple[float, ...]
    amplitude_deg: tuple[float, ...]
    period_s: tuple[float, ...]
    phase_rad: tuple[float, ...]

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: tuples of floats, one entry per joint."""
        centre = float_tuple("center_deg", given.center_deg, None, -180.0, 180.0)
        n = check_n_segments(len(centre), "the number of joints (entries of center_deg)")
        return {
            "center_deg": centre,
            "amplitude_deg": float_tuple("amplitude_deg", given.amplitude_deg, n, 0.0, 90.0),
            "period_s": float_tuple("period_s", given.period_s, n, positive=True, hi=1e5),
            "phase_rad": float_tuple("phase_rad", given.phase_rad, n, -100.0, 100.0),
        }

    @property
    def n_joints(self) -> int:
        """Number of joints (2 or 3)."""
        return len(self.center_deg)

    @property
    def peak_speed_rad_s(self) -> tuple[float, ...]:
        """(n,) peak joint speeds ``amp * 2 pi / period``, rad/s."""
        return tuple(
            math.radians(a) * 2.0 * math.pi / p for a, p in zip(self.amplitude_deg, self.period_s, strict=True)
        )

    def angles_rad(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint angles at ``t_s`` (s since the session start): (N,) -> (N, n) rad."""
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))[:, None]
        centre, amp, omega, phase = self._arrays()
        return centre + amp * np.sin(omega * t + phase)

    def velocities_rad_s(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Analytic joint velocities at ``t_s``: (N,) -> (N, n) rad/s (exactly 0 where the amplitude is 0)."""
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))[:, None]
        _, amp, omega, phase = self._arrays()
        return amp * omega * np.cos(omega * t + phase)

    def accelerations_rad_s2(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Analytic joint accelerations at ``t_s``: (N,) -> (N, n) rad/s^2."""
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))[:, None]
        _, amp, omega, phase = self._arrays()
        return -amp * omega * omega * np.sin(omega * t + phase)

    def speed_scaled(self, factor: float) -> TrajectorySpec:
        """The same sines ``factor`` times faster: periods divided by ``factor`` (> 0)."""
        scale = check_positive("speed scale", factor, 1e3)
        return TrajectorySpec(
            self.center_deg, self.amplitude_deg, tuple(p / scale for p in self.period_s), self.phase_rad
        )

    def _arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        return (
            np.radians(np.asarray(self.center_deg)),
            np.radians(np.asarray(self.amplitude_deg)),
            2.0 * np.pi / np.asarray(self.period_s),
            np.asarray(self.phase_rad),
        )


@runtime_checkable
class JointTrajectory(Protocol):
    """Any joint motion the simulator can follow: ``TrajectorySpec`` or ``bsp_ros.core.planning.PlannedTrajectory``."""

    @property
    def n_joints(self) -> int:
        """Number of joints (2 or 3)."""
        ...

    @property
    def peak_speed_rad_s(self) -> tuple[float, ...]:
        """(n,) peak joint speeds, rad/s."""
        ...

    def angles_rad(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint angles at ``t_s`` (s since the session start): (N,) -> (N, n) rad."""
        ...

    def velocities_rad_s(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint velocities at ``t_s``: (N,) -> (N, n) rad/s."""
        ...


def joint_accelerations_rad_s2(trajectory: TrajectorySpec | JointTrajectory, t_s: npt.ArrayLike) -> np.ndarray:
    """Joint accelerations of any trajectory: (N,) s -> (N, n) rad/s^2.

    The trajectory's own ``accelerations_rad_s2`` where it has one (``TrajectorySpec``, a planned
    trajectory), else a central difference of its velocities over +-0.1 ms.
    """
    own = getattr(trajectory, "accelerations_rad_s2", None)
    if callable(own):
        return np.asarray(own(t_s), dtype=np.float64)
    t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))
    h = _ACCELERATION_STEP_S
    return (trajectory.velocities_rad_s(t + h) - trajectory.velocities_rad_s(t - h)) / (2.0 * h)


@normalising
@dataclass(frozen=True)
class MultiSineTrajectory:
    """Per joint a sum of sines, ``q_j(t) = centre_j + sum_k amp_jk sin(2 pi t / period_jk + phase_jk)``.

    Short periods accelerate the arm at a given peak speed (the acceleration of a sine is its speed times its
    angular frequency), and two or more incommensurate periods per joint keep the acceleration from being
    proportional to the angle's deviation, as a single sine's is: there the inertial torque looks like a stiffness
    or a gravity term, here it does not. Build one with :meth:`within_speed`.

    Attributes
    ----------
    center_deg : (n,) operating point, deg.
    amplitude_deg, period_s, phase_rad : (n, k) the sines of each joint, deg, s, rad.
    """

    center_deg: tuple[float, ...]
    amplitude_deg: tuple[tuple[float, ...], ...]
    period_s: tuple[tuple[float, ...], ...]
    phase_rad: tuple[tuple[float, ...], ...]

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: tuples of floats, one row per joint."""
        centre = float_tuple("center_deg", given.center_deg, None, -180.0, 180.0)
        n = check_n_segments(len(centre), "the number of joints (entries of center_deg)")
        if {len(given.amplitude_deg), len(given.period_s), len(given.phase_rad)} != {n}:
            raise InputError(f"amplitude_deg, period_s and phase_rad need one row per joint ({n})")
        periods = tuple(
            float_tuple(f"period_s[{j}]", row, None, hi=1e5, positive=True) for j, row in enumerate(given.period_s)
        )
        out = {"center_deg": centre, "period_s": periods}
        for name, rows, lo, hi in (
            ("amplitude_deg", given.amplitude_deg, 0.0, 90.0),
            ("phase_rad", given.phase_rad, -100.0, 100.0),
        ):
            out[name] = tuple(float_tuple(f"{name}[{j}]", row, len(periods[j]), lo, hi) for j, row in enumerate(rows))
        return out

    @classmethod
    def within_speed(
        cls,
        center_deg: tuple[float, ...],
        period_s: tuple[tuple[float, ...], ...],
        peak_speed_rad_s: float,
        phase_rad: tuple[tuple[float, ...], ...],
    ) -> MultiSineTrajectory:
        """Each joint's sines sharing its speed equally, scaled so that its peak speed is ``peak_speed_rad_s``."""
        check_positive("peak speed (rad/s)", peak_speed_rad_s, 10.0)
        # Amplitudes giving each sine the same peak speed, small enough for any period, then scaled to the peak.
        small = tuple(tuple(1e-3 * p for p in row) for row in period_s)
        unit = cls(center_deg, small, period_s, phase_rad)
        scale = peak_speed_rad_s / np.asarray(unit.peak_speed_rad_s)
        amplitudes = tuple(tuple(a * s for a in row) for row, s in zip(small, scale, strict=True))
        return cls(center_deg, amplitudes, period_s, phase_rad)

    @property
    def n_joints(self) -> int:
        """Number of joints (2 or 3)."""
        return len(self.center_deg)

    @property
    def peak_speed_rad_s(self) -> tuple[float, ...]:
        """(n,) peak joint speeds over the sines' common cycle (sampled at 20 Hz over 2000 s), rad/s."""
        t = np.arange(0.0, 2000.0, 0.05)
        return tuple(float(v) for v in np.abs(self.velocities_rad_s(t)).max(axis=0))

    def angles_rad(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint angles at ``t_s`` (s since the session start): (N,) -> (N, n) rad."""
        amp, omega, phase, t = self._arrays(t_s)
        return np.radians(np.asarray(self.center_deg)) + (amp * np.sin(omega * t + phase)).sum(axis=-1)

    def velocities_rad_s(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Analytic joint velocities at ``t_s``: (N,) -> (N, n) rad/s."""
        amp, omega, phase, t = self._arrays(t_s)
        return (amp * omega * np.cos(omega * t + phase)).sum(axis=-1)

    def accelerations_rad_s2(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Analytic joint accelerations at ``t_s``: (N,) -> (N, n) rad/s^2."""
        amp, omega, phase, t = self._arrays(t_s)
        return (-amp * omega * omega * np.sin(omega * t + phase)).sum(axis=-1)

    def _arrays(self, t_s: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        width = max(len(row) for row in self.period_s)

        def padded(rows: tuple[tuple[float, ...], ...], fill: float) -> np.ndarray:
            return np.array([list(row) + [fill] * (width - len(row)) for row in rows], dtype=np.float64)

        amp = np.radians(padded(self.amplitude_deg, 0.0))
        omega = 2.0 * np.pi / padded(self.period_s, 1.0)
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))[:, None, None]
        return amp, omega, padded(self.phase_rad, 0.0), t


@dataclass(frozen=True)
class TrunkTiltedTrajectory:
    """``trajectory`` (angles relative to an upright trunk) recorded with the trunk tilted by ``tilt_rad``: the same
    angles relative to the trunk, so the shoulder's world angle turns by the tilt (a second posture of a plan)."""

    trajectory: JointTrajectory
    tilt_rad: float

    @property
    def n_joints(self) -> int:
        """The trajectory's joints."""
        return int(self.trajectory.n_joints)

    @property
    def peak_speed_rad_s(self) -> tuple[float, ...]:
        """(n,) the trajectory's peak joint speeds, rad/s: a constant tilt leaves them as they are."""
        return tuple(self.trajectory.peak_speed_rad_s)

    def angles_rad(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint angles (N, n), rad: the trunk-relative ones with the shoulder turned by the tilt."""
        q = np.array(self.trajectory.angles_rad(t_s), dtype=np.float64)
        q[..., 0] += self.tilt_rad
        return q

    def velocities_rad_s(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint velocities (N, n), rad/s: a constant tilt leaves them as they are."""
        return np.asarray(self.trajectory.velocities_rad_s(t_s), dtype=np.float64)

    def accelerations_rad_s2(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint accelerations (N, n), rad/s^2, the trajectory's own."""
        return joint_accelerations_rad_s2(self.trajectory, t_s)
