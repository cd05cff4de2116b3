"""The derivative filters widen for a faster motion and for nothing else (slow sines, noise, dropouts)."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core.joint_angles import KinematicsConfig
from bsp_ros.core.motion_band import config_for_motion, motion_top_hz

RATE_HZ = 100.0
T_S = np.arange(0.0, 120.0, 1.0 / RATE_HZ)


def _sines(periods_s: tuple[float, ...], amplitudes_rad: tuple[float, ...]) -> np.ndarray:
    wave = sum(
        a * np.sin(2 * np.pi * T_S / p + k) for k, (p, a) in enumerate(zip(periods_s, amplitudes_rad, strict=True))
    )
    return np.column_stack([wave, 0.5 * wave, 0.2 * wave])


def test_the_papers_slow_sines_keep_the_default_filters() -> None:
    q = _sines((22.0,), (0.1,)) + np.random.default_rng(1).normal(0.0, 1e-3, (T_S.size, 3))
    config, notes = config_for_motion(KinematicsConfig(), q, RATE_HZ)
    assert config == KinematicsConfig() and notes == []


def test_a_two_sine_motion_raises_the_direction_filter_to_pass_its_fast_sine() -> None:
    q = _sines((2.1, 7.9), (0.05, 0.19))
    assert motion_top_hz(q, RATE_HZ) == pytest.approx(1 / 2.1, abs=0.02)
    config, notes = config_for_motion(KinematicsConfig(), q, RATE_HZ)
    assert config.direction_cutoff_hz == pytest.approx(2.5 / 2.1, abs=0.05) and "0.48 Hz" in notes[0]
    assert config.dynamics_cutoff_hz == KinematicsConfig().dynamics_cutoff_hz  # 2 x 0.48 Hz is under 1 Hz


def test_marker_noise_alone_never_reads_as_fast_motion() -> None:
    rng = np.random.default_rng(2)
    q = _sines((22.0,), (0.016,)) + rng.normal(0.0, 0.02, (T_S.size, 3))  # noise larger than the motion
    assert config_for_motion(KinematicsConfig(), q, RATE_HZ)[1] == []


def test_dropouts_do_not_shorten_the_spectrum() -> None:
    # Runs a few seconds long between gaps once put the slow motion's leakage at 0.33 Hz.
    q = _sines((22.0,), (0.1,))
    rng = np.random.default_rng(3)
    for start in rng.integers(0, T_S.size - 40, 60):
        q[start : start + 30] = np.nan
    assert config_for_motion(KinematicsConfig(), q, RATE_HZ)[1] == []
    assert motion_top_hz(q[:1500], RATE_HZ) == 0.0  # 15 s: too short to tell
