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
# NOISE_BAND_HZ, where no arm moved by a rehabilitation robot has content): a white-noise bin's power is
# exponential, so one beyond 30 times the median comes about once in 10^9 bins (at 10 times, once in 1000:
# with marker noise above a slow wrist's motion that was enough to widen the filters).
FLOOR_FACTOR = 30.0
NOISE_BAND_HZ = (2.0, 4.0)
# Cutoffs at these multiples of the top frequency: the direction velocity's second-order zero-phase filter then
# passes it at 99.4 % (at 0.5 Hz, a 0.48 Hz component kept 95 %, and a multi-sine's velocity changed sign off
# its true reversals: Coulomb's sign wrong for hundreds of samples, the fit 9 times the noise).
DIRECTION_FACTOR = 2.5
# The estimate needs most of a session of at least this span (a shorter one cannot resolve 0.1-0.2 Hz).
MIN_FINITE_SHARE = 0.8
MIN_SPAN_S = 20.0
DYNAMICS_FACTOR = 2.0


def motion_top_hz(q_rad: np.ndarray, rate_hz: float) -> float:
    """The frequency below which :data:`POWER_SHARE` of the angles' motion power lies, Hz (0 if none).

    Parameters
    ----------
    q_rad : (N, n) joint angles on a uniform grid (NaN frames allowed, bridged here; with under 80 % of the
        frames finite or under 20 s in all, 0), rad.
    rate_hz : the grid's rate, Hz.
    """
    finite = np.isfinite(q_rad).all(axis=1)
    # The spectrum needs the whole session: a run between dropouts seconds long would put the slow motion's
    # leakage at its own lowest bins (a 4 s run: 0.33 Hz) and widen the filters for nothing. Gaps are bridged
    # linearly for this estimate only (their kinks carry no power that matters against the motion's).
    if finite.sum() < MIN_FINITE_SHARE * finite.size or finite.sum() < 64:
        return 0.0
    index = np.arange(finite.size)
    run = np.column_stack([np.interp(index, index[finite], q_rad[finite, j]) for j in range(q_rad.shape[1])])
    length = run.shape[0]
    if length / rate_hz < MIN_SPAN_S:
        return 0.0
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
