"""Marker kinematics resampled onto other stamps (the wrench's)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from bsp_ros.core.joint_angles.config import MarkerKinematics


def resample_kinematics(kinematics: MarkerKinematics, t_ns: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Interpolate angles and direction velocities onto other stamps (the wrench's).

    Parameters
    ----------
    kinematics : angles on the marker grid.
    t_ns : (N,) int64 target stamps.

    Returns
    -------
    q_rad : (N, n) angles (rad), NaN where invalid.
    velocity_rad_s : (N, n) direction velocities (rad/s), NaN where invalid.
    valid : (N,) bool, True where both neighbouring grid frames are valid.
    """
    lower_c, frac, inside = _neighbours(kinematics.t_ns, t_ns)
    upper_c, frac = lower_c + 1, frac[:, None]

    def blend(values: np.ndarray) -> np.ndarray:
        # take gathers rows a third faster than fancy indexing (the same values)
        return (1.0 - frac) * values.take(lower_c, axis=0) + frac * values.take(upper_c, axis=0)

    q_rad = blend(kinematics.q_rad)
    velocity = blend(kinematics.direction_velocity_rad_s)
    valid = inside & np.isfinite(q_rad).all(axis=1) & np.isfinite(velocity).all(axis=1)
    q_rad[~valid] = np.nan
    velocity[~valid] = np.nan
    return q_rad, velocity, valid


def _neighbours(grid: np.ndarray, t_ns: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For each stamp of ``t_ns``: the grid frame before it (N,) (clipped to the grid), its fraction of the step
    to the next frame (N,), and whether it lies on the grid (N,) bool."""
    target = np.asarray(t_ns, dtype=np.int64)
    step = float(grid[1] - grid[0]) if grid.size > 1 else 1.0
    position = (target - grid[0]).astype(np.float64) / step
    lower = np.floor(position).astype(np.int64)
    inside = (lower >= 0) & (lower < grid.size - 1)
    lower_c = np.clip(lower, 0, max(grid.size - 2, 0))
    frac = position - lower_c
    exact_last = position == grid.size - 1
    lower_c = np.where(exact_last, grid.size - 2, lower_c)
    frac = np.where(exact_last, 1.0, frac)
    return lower_c, frac, inside | exact_last


def valid_stamps(kinematics: MarkerKinematics, t_ns: npt.ArrayLike) -> np.ndarray:
    """(N,) bool: the ``valid`` of :func:`resample_kinematics` without interpolating anything (on the grid, both
    neighbouring frames finite: a blend of finite frames is finite, and one with a NaN frame is not)."""
    lower_c, _, inside = _neighbours(kinematics.t_ns, t_ns)
    finite = np.isfinite(kinematics.q_rad).all(axis=1) & np.isfinite(kinematics.direction_velocity_rad_s).all(axis=1)
    if finite.size < 2:
        return np.zeros(lower_c.size, dtype=bool)
    return np.asarray(inside & finite[lower_c] & finite[lower_c + 1])


def resample_motion(kinematics: MarkerKinematics, t_ns: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Velocities and accelerations (N, n) of :class:`MarkerKinematics` at other stamps (zeros if absent; NaN
    near gaps and the ends of runs)."""
    target = np.asarray(t_ns, dtype=np.int64)
    n = kinematics.q_rad.shape[1]
    if kinematics.velocity_rad_s is None or kinematics.acceleration_rad_s2 is None:
        return np.zeros((target.size, n)), np.zeros((target.size, n))
    grid = (kinematics.t_ns - kinematics.t_ns[0]).astype(np.float64)
    where = (target - kinematics.t_ns[0]).astype(np.float64)
    out = []
    for values in (kinematics.velocity_rad_s, kinematics.acceleration_rad_s2):
        # NaN (a gap or a run's edge) spreads to the samples beside it: those have no usable derivative.
        column = [np.interp(where, grid, values[:, j]) for j in range(n)]
        out.append(np.column_stack(column))
    return out[0], out[1]


def resample_with_motion(
    kinematics: MarkerKinematics, t_ns: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`resample_kinematics` with the joint velocities and accelerations of the inertial torques.

    Returns
    -------
    q_rad, velocity_rad_s, qd_rad_s, qdd_rad_s2 : (N, n) each.
    valid : (N,) bool, also False where the derivatives are unknown: near gaps and the ends of runs (the
        zero-phase filter's edge, hence the newest half second of a live window). Taken as a still arm there,
        the inertial torque would bias the fit; offline and live drop those samples alike.
    """
    q_rad, velocity, valid = resample_kinematics(kinematics, t_ns)
    qd, qdd = resample_motion(kinematics, t_ns)
    valid &= np.isfinite(qd).all(axis=1) & np.isfinite(qdd).all(axis=1)
    return q_rad, velocity, qd, qdd, valid
