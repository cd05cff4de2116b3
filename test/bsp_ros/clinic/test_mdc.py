"""Minimal detectable change: cycle splitting, the successive-difference SEM and MDC95 on simulated sessions."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from bsp_ros.clinic.mdc import (
    cycle_bounds,
    direction_reversals,
    mdc95_from_sem,
    pair_mdc95,
    parameter_key,
    repeatability,
    successive_difference_sem,
)
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.joint import identify_joint
from bsp_ros.core.simulation import human_arm_cell, simulate_cell


def test_successive_difference_sem_estimates_the_repeat_sd() -> None:
    rng = np.random.default_rng(0)
    repeats = 2.0 + 0.05 * rng.standard_normal(4000)
    assert successive_difference_sem(repeats) == pytest.approx(0.05, rel=0.05)


def test_successive_difference_sem_is_insensitive_to_slow_drift() -> None:
    rng = np.random.default_rng(1)
    drifting = np.linspace(0.0, 1.0, 4000) + 0.05 * rng.standard_normal(4000)
    assert drifting.std() > 0.25  # the plain SD is dominated by the drift
    assert successive_difference_sem(drifting) == pytest.approx(0.05, rel=0.05)


def test_mdc95_is_196_sqrt2_sem() -> None:
    assert mdc95_from_sem(0.1) == pytest.approx(1.96 * math.sqrt(2.0) * 0.1)
    assert pair_mdc95(0.1, 0.1) == pytest.approx(mdc95_from_sem(0.1))
    assert math.isnan(successive_difference_sem([1.0]))


def test_direction_reversals_of_a_noisy_sine_are_at_its_turning_points() -> None:
    rng = np.random.default_rng(2)
    t = np.linspace(0.0, 100.0, 10_001)
    velocity = np.cos(2 * np.pi * t / 20.0) + 0.05 * rng.standard_normal(t.size)  # position sin: turns at 5 + 10 k
    found = t[direction_reversals(velocity)]
    np.testing.assert_allclose(found, 5.0 + 10.0 * np.arange(found.size), atol=0.15)
    assert found.size == 10


def test_cycles_follow_the_joint_that_reverses_least() -> None:
    t = np.linspace(0.0, 100.0, 10_001)
    velocity = np.stack((np.cos(2 * np.pi * t / 20.0), np.cos(2 * np.pi * t / 7.0)), axis=1)
    bounds = cycle_bounds(velocity)
    lengths = np.array([b - a for a, b in bounds]) * (t[1] - t[0])
    np.testing.assert_allclose(lengths, 20.0, atol=0.2)  # one full period of the slow joint each
    assert all(a2 == b1 for (_, b1), (a2, _) in itertools.pairwise(bounds))


@pytest.mark.slow
def test_cycle_estimates_scatter_around_the_truth_by_the_sem() -> None:
    simulated = simulate_cell(human_arm_cell(duration_s=120.0, seed=3))
    data = identification_data_from_session(simulated.session)
    result = repeatability(data)
    assert result.n_valid_cycles >= 4 and result.message == ""
    truth = {
        **{
            f"segments.{s}.static_moment_kgm": v
            for s, v in zip(simulated.truth.segment_names, simulated.truth.static_moments_kgm, strict=True)
        },
        **{f"joints.{j}.coulomb_nm": v for j, v in zip(simulated.truth.joint_names, (0.5, 0.28, 0.06), strict=True)},
    }
    session = identify_joint(data)
    for i, name in enumerate(session.names):
        key = parameter_key(name, 3)
        cycles = np.asarray(result.cycle_values[key])
        sem = result.sem[key]
        rms_from_truth = float(np.sqrt(np.mean((cycles - truth[key]) ** 2)))
        # Each cycle is one measurement: its error from the truth is of the order of the SEM ...
        assert 0.25 * sem < rms_from_truth < 4.0 * sem, key
        # ... and a one-cycle SEM is at least the whole-session estimate's uncertainty (conservative).
        assert sem > 0.8 * session.std[i], key
    assert result.to_json()["parameters"]["joints.elbow.coulomb_nm"]["mdc95"] == pytest.approx(
        mdc95_from_sem(result.sem["joints.elbow.coulomb_nm"])
    )


def test_too_few_cycles_give_no_sem_and_say_why() -> None:
    simulated = simulate_cell(human_arm_cell(duration_s=40.0, seed=4))
    result = repeatability(identification_data_from_session(simulated.session))
    assert result.sem == {} and "need 3" in result.message
