"""The motion's frequency band, and the derivative filters widened to pass it (a faster protocol's reversals)."""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from bsp_ros.core.joint_angles import KinematicsConfig

# The share of the angles' (detrended) power below the motion's top frequency.
POWER_SHARE = 0.99
# A bin counts as motion only where its power is this many times the noise floor (the median bin of
# NOISE_BAND_HZ, where no arm moved by a rehabilitation robot has content).
FLOOR_FACTOR = 10.0
NOISE_BAND_HZ = (2.0, 4.0)
# Cutoffs at these multiples of the top frequency: the direction velocity's second-order zero-phase filter then
# passes it at 99.4 % (at 0.5 Hz, a 0.48 Hz component kept 95 %, and a multi-sine's velocity changed sign off
# its true reversals: Coulomb's sign wrong for hundreds of samples, the fit 9 times the noise).
DIRECTION_FACTOR = 2.5
DYNAMICS_FACTOR = 2.0


def motion_top_hz(q_rad: np.ndarray, rate_hz: float) -> float:
    """The frequency below which :data:`POWER_SHARE` of the angles' motion power lies, Hz (0 if none).

    Parameters
    ----------
    q_rad : (N, n) joint angles on a uniform grid (NaN frames allowed: the longest finite run is used), rad.
    rate_hz : the grid's rate, Hz.
    """
    finite = np.isfinite(q_rad).all(axis=1)
    best, begin = (0, 0), None
    for k, ok in enumerate(np.append(finite, False)):
        if ok and begin is None:
            begin = k
        elif not ok and begin is not None:
            best = max(best, (k - begin, begin))
            begin = None
    length, start = best
    if length < 64:
        return 0.0
    run = q_rad[start : start + length]
    run = run - _linear_trend(run)
    power = np.abs(np.fft.rfft(run * np.hanning(length)[:, None], axis=0)) ** 2
    freqs = np.fft.rfftfreq(length, 1.0 / rate_hz)
    top = 0.0
    in_band = (freqs >= NOISE_BAND_HZ[0]) & (freqs <= NOISE_BAND_HZ[1])
    for j in range(power.shape[1]):
        column = power[:, j].copy()
        if in_band.any():
            column[column < FLOOR_FACTOR * np.median(column[in_band])] = 0.0
        # Nothing at or above the noise band is motion: single noise bins there reach any multiple of the floor.
        column[freqs >= NOISE_BAND_HZ[0]] = 0.0
        column[0] = 0.0
        total = column.sum()
        if total <= 0.0:
            continue
        share = np.cumsum(column) / total
        top = max(top, float(freqs[int(np.searchsorted(share, POWER_SHARE))]))
    return top


def _linear_trend(values: np.ndarray) -> np.ndarray:
    x = np.arange(values.shape[0], dtype=np.float64)
    x -= x.mean()
    slope = (x[:, None] * (values - values.mean(axis=0))).sum(axis=0) / (x * x).sum()
    return np.asarray(values.mean(axis=0) + x[:, None] * slope)


def config_for_motion(
    config: KinematicsConfig, q_rad: np.ndarray, rate_hz: float
) -> tuple[KinematicsConfig, list[str]]:
    """``config`` with the direction and dynamics cutoffs raised (never lowered) to pass the motion's band.

    A slow protocol (the paper's sines, a planned one: under 0.2 Hz) keeps the defaults; a faster one (short
    periods to excite inertia) gets cutoffs at :data:`DIRECTION_FACTOR` and :data:`DYNAMICS_FACTOR` times its
    top frequency, below the angle cutoff. Returns the config and a note when a cutoff was raised.
    """
    top = motion_top_hz(q_rad, rate_hz)
    ceiling = 0.5 * config.cutoff_hz
    direction = min(max(config.direction_cutoff_hz, DIRECTION_FACTOR * top), max(ceiling, config.direction_cutoff_hz))
    dynamics = min(max(config.dynamics_cutoff_hz, DYNAMICS_FACTOR * top), max(ceiling, config.dynamics_cutoff_hz))
    if direction == config.direction_cutoff_hz and dynamics == config.dynamics_cutoff_hz:
        return config, []
    note = (
        f"the motion reaches {top:.2g} Hz: direction filter {direction:.2g} Hz (from {config.direction_cutoff_hz:g}), "
        f"dynamics filter {dynamics:.2g} Hz (from {config.dynamics_cutoff_hz:g})"
    )
    return dataclasses.replace(config, direction_cutoff_hz=direction, dynamics_cutoff_hz=dynamics), [note]
