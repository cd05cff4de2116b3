"""The MDC from retest pairs (against known error), which sessions pair, and within-session cycles via the pipeline."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from bsp_ros.clinic.cycles import cycle_bounds, cycle_repeatability, direction_reversals
from bsp_ros.clinic.mdc import (
    DAY_NS,
    icc_agreement,
    mdc95_from_sem,
    pooled_error,
    retest_pairs,
    successive_difference_sem,
    t95,
)
from bsp_ros.clinic.store.estimate import parse_estimate
from bsp_ros.clinic.store.samples import SAMPLE_START_NS, sample_estimate
from bsp_ros.core.simulation import human_arm_cell, simulate_cell


def test_pooled_sem_recovers_the_day_to_day_error() -> None:
    rng = np.random.default_rng(0)
    true_sem = 0.03
    level = rng.normal(0.8, 0.2, 4000)  # subjects differ; each is measured twice with error SEM
    pairs = [
        (a + true_sem * e1, a + true_sem * e2, f"S{i % 40}")
        for i, (a, e1, e2) in enumerate(zip(level, rng.standard_normal(4000), rng.standard_normal(4000), strict=True))
    ]
    error = pooled_error(pairs, "cell")
    assert error.sem == pytest.approx(true_sem, rel=0.04)
    assert error.mdc95 == pytest.approx(mdc95_from_sem(error.sem), rel=0.002)  # t -> 1.96 with many pairs
    # ICC = between-subject variance / (between + error variance) = 0.04 / (0.04 + 0.0009).
    assert error.icc == pytest.approx(0.04 / 0.0409, abs=0.01) and error.n_subjects == 40


def test_few_pairs_give_no_mdc_and_a_wider_one_until_many() -> None:
    assert pooled_error([(1.0, 1.1, "A")] * 4, "subject").mdc95 is None
    five = pooled_error([(1.0, 1.1, "A"), (1.0, 0.9, "A")] * 2 + [(1.0, 1.0, "A")], "subject")
    assert five.n_pairs == 5 and five.icc is None  # one subject: no between-subject spread, no ICC
    assert five.mdc95 == pytest.approx(t95(5) * math.sqrt(0.04 / 5)) and t95(5) > 2.5 > 1.96
    # A systematic shift between test and retest is error too: the SD is taken about zero.
    shifted = pooled_error([(1.0, 1.05, "A")] * 6, "subject")
    assert shifted.sem == pytest.approx(0.05 / math.sqrt(2))


def test_icc_of_a_perfectly_repeatable_table_is_one() -> None:
    assert icc_agreement([[1.0, 1.0], [2.0, 2.0], [3.0, 3.0]]) == pytest.approx(1.0)


def _record(
    seed: int,
    day: int,
    hour: int,
    *,
    subject: str = "P1",
    retest: bool = False,
    valid: bool = True,
    arm: str | None = "left",
):
    estimate = sample_estimate(seed, start_time_ns=SAMPLE_START_NS + day * DAY_NS + hour * 3_600 * 10**9, valid=valid)
    return replace(parse_estimate(estimate, subject, retest=retest, arm=arm), id=seed)


def test_a_retest_pairs_with_the_same_days_valid_session_of_the_same_arm() -> None:
    records = [
        _record(1, 0, 0),
        _record(2, 0, 1, retest=True),  # pairs with 1
        _record(3, 1, 0, valid=False),
        _record(4, 1, 1, retest=True),  # its day's session is not valid: no pair
        _record(5, 2, 0, arm="right"),
        _record(6, 2, 1, retest=True),  # left arm retest, right arm session: no pair
        _record(7, 3, 0, subject="P2"),
        _record(8, 3, 1, retest=True),  # P1's retest, P2's session: no pair
        _record(9, 4, 16),  # 23:00 UTC
        _record(10, 5, 0, retest=True),  # the next day: no pair
    ]
    assert [(p.test.id, p.retest.id) for p in retest_pairs(records)] == [(1, 2)]


def test_successive_difference_sem_estimates_the_repeat_sd() -> None:
    rng = np.random.default_rng(0)
    assert successive_difference_sem(2.0 + 0.05 * rng.standard_normal(4000)) == pytest.approx(0.05, rel=0.05)


def test_direction_reversals_of_a_noisy_sine_are_at_its_turning_points() -> None:
    t = np.linspace(0.0, 60.0, 6001)
    velocity = np.cos(2 * np.pi * t / 20.0) + 0.05 * np.random.default_rng(1).standard_normal(t.size)
    reversals = t[direction_reversals(velocity)]
    np.testing.assert_allclose(reversals, [5.0, 15.0, 25.0, 35.0, 45.0, 55.0], atol=0.3)
    assert len(cycle_bounds(velocity[:, None])) == 2


@pytest.mark.slow
def test_cycles_identified_through_the_pipeline_scatter_around_the_truth() -> None:
    simulated = simulate_cell(human_arm_cell(duration_s=120.0, seed=3))
    found = cycle_repeatability(simulated.session)
    assert found.n_valid_cycles >= 4 and found.message == ""
    truth = {
        f"joints.{j}.coulomb_nm": v for j, v in zip(("shoulder", "elbow", "wrist"), (0.5, 0.28, 0.06), strict=True)
    }
    for key, true in truth.items():
        cycles = np.asarray(found.cycle_values[key])
        assert 0.2 * found.sem[key] < float(np.sqrt(np.mean((cycles - true) ** 2))) < 5 * found.sem[key] + 0.01 * true
    assert found.to_json()["parameters"]["joints.elbow.coulomb_nm"]["n"] == found.n_valid_cycles


def test_too_few_cycles_give_no_sem_and_say_why() -> None:
    found = cycle_repeatability(simulate_cell(human_arm_cell(duration_s=40.0, seed=4)).session)
    assert found.sem == {} and "need 3" in found.message
