"""Model check: resistance that grows with the speed of motion in one direction only, as a stretch reflex does.

Spasticity is a velocity-dependent increase in the resistance to stretch (Lance 1980): above a threshold speed a
stretched muscle's reflex resists the motion, with a delay of 30-60 ms, in the direction that stretches it only.
Viscous friction grows with speed in both directions alike; a relaxed arm's friction barely changes with it at
a robot's slow speeds. So each joint's residual, averaged over half-second bins, is regressed on the speed in
each direction of motion apart: a clear slope in one direction and none (or the other sign) in the other is
named as possible spasticity, the speed-dependent part the relaxed-arm model does not hold.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SpeedDependence", "speed_dependence"]

# Residual bins, s: long enough that neighbouring bins' residuals are nearly independent, short against a stretch.
BIN_S = 0.5

# A slope this many standard errors from zero is clear; below the lower bound, absent.
CLEAR_T = 5.0
ABSENT_T = 2.0


@dataclass(frozen=True, kw_only=True)
class SpeedDependence:
    """One joint's resistance against speed, per direction of motion.

    Attributes
    ----------
    direction : +1 or -1, the direction of motion (the sign of the joint velocity) whose resistance grows with
        speed while the other's does not, or 0 where none does so alone.
    increase_nm : how much the resistance grows from the slow to the fast end of that direction's speeds, Nm.
    fast_rad_s : the fast end (90th percentile of that direction's speeds), rad/s.
    t_values : (2,) the slopes' t values, for motion in the + and - direction.
    """

    direction: int
    increase_nm: float
    fast_rad_s: float
    t_values: tuple[float, float]


def _slope(speed: np.ndarray, resistance: np.ndarray) -> tuple[float, float]:
    """Least-squares slope of ``resistance`` on ``speed`` and its t value (0, 0 with fewer than 8 bins)."""
    if speed.size < 8:
        return 0.0, 0.0
    dx, dy = speed - speed.mean(), resistance - resistance.mean()
    sxx = float(dx @ dx)
    if sxx <= 0:
        return 0.0, 0.0
    slope = float(dx @ dy) / sxx
    residual = dy - slope * dx
    se = np.sqrt(max(float(residual @ residual) / (speed.size - 2) / sxx, 1e-300))
    return slope, slope / se


def speed_dependence(t_ns: np.ndarray, velocity_rad_s: np.ndarray, residual_nm: np.ndarray) -> SpeedDependence:
    """Whether one joint's resistance grows with speed in one direction of motion only.

    Parameters
    ----------
    t_ns : (N,) stamps, ns.
    velocity_rad_s : (N,) the joint's direction-of-motion velocity, rad/s.
    residual_nm : (N,) the fit's torque residual at the joint, Nm (NaN off its rows); the measured joint torque is
        the one the arm exerts on the handle, so a resistance to the motion has the motion's sign.
    """
    t_s = (t_ns - t_ns[0]) * 1e-9
    index = np.floor(t_s / BIN_S).astype(np.int64)
    n_bins = int(index[-1]) + 1 if index.size else 0
    finite = np.isfinite(residual_nm) & (velocity_rad_s != 0)
    slopes, t_values, fast = [], [], []
    for sign in (1.0, -1.0):
        rows = finite & (np.sign(velocity_rad_s) == sign)
        counts = np.bincount(index[rows], minlength=n_bins)
        keep = counts >= max(3, int(np.median(counts[counts > 0])) // 2) if counts.any() else counts > 0
        speed = np.bincount(index[rows], np.abs(velocity_rad_s[rows]), n_bins)[keep] / counts[keep]
        resistance = sign * np.bincount(index[rows], residual_nm[rows], n_bins)[keep] / counts[keep]
        slope, t_value = _slope(speed, resistance)
        slopes.append(slope)
        t_values.append(t_value)
        ends = np.quantile(speed, (0.1, 0.9)) if speed.size else np.zeros(2)
        fast.append((float(ends[0]), float(ends[1])))
    out = SpeedDependence(direction=0, increase_nm=0.0, fast_rad_s=0.0, t_values=(t_values[0], t_values[1]))
    for d, other in ((0, 1), (1, 0)):
        if t_values[d] > CLEAR_T and t_values[other] < ABSENT_T:
            slow, quick = fast[d]
            increase = slopes[d] * (quick - slow)
            return SpeedDependence(
                direction=1 if d == 0 else -1, increase_nm=increase, fast_rad_s=quick, t_values=out.t_values
            )
    return out
