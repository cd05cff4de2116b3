"""A planned joint trajectory: knots with angles and velocities, joined by cubic Hermite pieces."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.interpolate import CubicHermiteSpline

from bsp_ros.core.model import absolute_angles_rad, joint_positions_m
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_array

# Samples per knot interval when a property of the whole path (peak speed, range) is evaluated.
_SAMPLES_PER_PIECE = 16


class PlannedTrajectory:
    """Joint motion through knots ``(t, q, qdot)``: C1, cubic between knots, held at rest outside them.

    The same interface as ``bsp_ros.core.simulation.TrajectorySpec`` (``angles_rad``, ``velocities_rad_s``,
    ``n_joints``, ``peak_speed_rad_s``), so the simulator can follow it.

    Parameters
    ----------
    t_s : (K,) knot times (s since the session start), strictly increasing, the first 0.
    q_rad : (K, n) joint angles at the knots (rad, docs/contract.md conventions: q1 absolute, q2, q3 relative).
    qdot_rad_s : (K, n) joint velocities at the knots (rad/s); the first and last must be 0 (start and
        end at rest).

    Raises
    ------
    InputError
        On non-finite values, wrong shapes, unordered knots, or motion at either end.
    """

    def __init__(self, t_s: npt.ArrayLike, q_rad: npt.ArrayLike, qdot_rad_s: npt.ArrayLike) -> None:
        t = check_finite_array("knot times (s)", t_s, (None,))
        q = check_finite_array("knot angles (rad)", q_rad, (t.size, None))
        qdot = check_finite_array("knot velocities (rad/s)", qdot_rad_s, q.shape)
        if t.size < 2:
            raise InputError(f"a planned trajectory needs at least 2 knots, got {t.size}")
        if q.shape[1] not in (2, 3):
            raise InputError(f"a planned trajectory has 2 or 3 joints, got {q.shape[1]}")
        if t[0] != 0.0:
            raise InputError(f"the first knot must be at t = 0 s, got {t[0]!r}")
        steps = np.diff(t)
        if (steps <= 0).any():
            at = int(np.argmin(steps)) + 1
            raise InputError(f"knot times must increase strictly: t[{at}] = {t[at]!r} after {t[at - 1]!r}")
        if np.abs(qdot[[0, -1]]).max() > 0:
            raise InputError(
                f"a planned trajectory starts and ends at rest, got end velocities {qdot[[0, -1]].tolist()}"
            )
        if np.abs(q).max() > 2 * math.pi:
            raise InputError(f"knot angles must be within +-2 pi rad, got {float(np.abs(q).max())!r}")
        self._t = t
        self._q = q
        self._qdot = qdot
        self._spline = CubicHermiteSpline(t, q, qdot, axis=0, extrapolate=False)
        self._velocity = self._spline.derivative()
        self._dense: tuple[np.ndarray, np.ndarray] | None = None

    def _dense_path(self) -> tuple[np.ndarray, np.ndarray]:
        """Angles and velocities on :meth:`dense_times_s` (computed once, on first use)."""
        if self._dense is None:
            dense = self.dense_times_s()
            self._dense = (self.angles_rad(dense), self.velocities_rad_s(dense))
        return self._dense

    # the TrajectorySpec interface ---------------------------------------------------------------------
    @property
    def n_joints(self) -> int:
        """Number of joints (2 or 3)."""
        return int(self._q.shape[1])

    @property
    def peak_speed_rad_s(self) -> tuple[float, ...]:
        """(n,) largest joint speed along the path, rad/s."""
        return tuple(float(v) for v in np.abs(self._dense_path()[1]).max(axis=0))

    def angles_rad(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint angles at ``t_s`` (s since the session start): (N,) -> (N, n) rad; held at the end knots."""
        t = np.clip(np.atleast_1d(np.asarray(t_s, dtype=np.float64)), self._t[0], self._t[-1])
        return np.asarray(self._spline(t))

    def velocities_rad_s(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint velocities at ``t_s``: (N,) -> (N, n) rad/s; 0 before the first and after the last knot."""
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))
        inside = (t >= self._t[0]) & (t <= self._t[-1])
        out = np.zeros((t.size, self.n_joints))
        out[inside] = self._velocity(t[inside])
        return out

    # more -----------------------------------------------------------------------------------------------
    @property
    def duration_s(self) -> float:
        """Time of the last knot, s."""
        return float(self._t[-1])

    @property
    def knots(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Copies of ``(t_s (K,), q_rad (K, n), qdot_rad_s (K, n))``."""
        return self._t.copy(), self._q.copy(), self._qdot.copy()

    @property
    def range_rad(self) -> tuple[np.ndarray, np.ndarray]:
        """(n,) lowest and (n,) highest angle each joint reaches along the path, rad."""
        angles = self._dense_path()[0]
        return angles.min(axis=0), angles.max(axis=0)

    def to_dict(self) -> dict[str, list[float] | list[list[float]]]:
        """The knots as plain lists: ``t_s``, ``q_rad``, ``qdot_rad_s``."""
        return {"t_s": self._t.tolist(), "q_rad": self._q.tolist(), "qdot_rad_s": self._qdot.tolist()}

    @classmethod
    def from_dict(cls, data: Any) -> PlannedTrajectory:
        """Read back what :meth:`to_dict` wrote; InputError on a missing key."""
        try:
            return cls(data["t_s"], data["q_rad"], data["qdot_rad_s"])
        except (KeyError, TypeError) as error:
            raise InputError(f"planned trajectory: missing or malformed field {error}") from None

    def dense_times_s(self, per_piece: int = _SAMPLES_PER_PIECE) -> np.ndarray:
        """Times that resolve every cubic piece (``per_piece`` per knot interval), s."""
        fractions = np.linspace(0.0, 1.0, per_piece, endpoint=False)
        inner = (self._t[:-1, None] + np.diff(self._t)[:, None] * fractions[None, :]).ravel()
        return np.append(inner, self._t[-1])

    def accelerations_rad_s2(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint accelerations at ``t_s``: (N,) -> (N, n) rad/s^2 (0 outside the knots)."""
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))
        inside = (t >= self._t[0]) & (t <= self._t[-1])
        out = np.zeros((t.size, self.n_joints))
        out[inside] = self._spline.derivative(2)(t[inside])
        return out

    def sample_times_s(self, rate_hz: float) -> np.ndarray:
        """A uniform grid from 0 to the end (included) at ``rate_hz``, s."""
        count = math.floor(self.duration_s * rate_hz + 1e-9) + 1
        times = np.arange(count) / rate_hz
        return times if times[-1] == self.duration_s else np.append(times, self.duration_s)


def handle_poses_world(q_rad: npt.ArrayLike, lengths_m: npt.ArrayLike, shoulder_yz_m: npt.ArrayLike) -> np.ndarray:
    """Handle (contact point) poses in ``world`` from joint angles: planar forward kinematics.

    Parameters
    ----------
    q_rad : (N, n) joint angles (rad).
    lengths_m : (n,) segment lengths (m).
    shoulder_yz_m : (2,) shoulder position ``[y, z]`` in ``world`` (m).

    Returns
    -------
    (N, 3) ``[y (m), z (m), pitch (rad)]``: the contact point and the angle of the last segment from +y
    (positive about +x, docs/contract.md conventions).
    """
    q = np.atleast_2d(np.asarray(q_rad, dtype=np.float64))
    points = joint_positions_m(q, lengths_m)[:, -1, :] + np.asarray(shoulder_yz_m, dtype=np.float64)[None, :]
    pitch = absolute_angles_rad(q)[:, -1]
    return np.column_stack((points, pitch))
