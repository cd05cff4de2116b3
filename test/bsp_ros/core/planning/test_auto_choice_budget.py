"""`bsp plan --passive auto` predicts the std of the model `bsp identify --passive auto` chooses, with the spread of
the models its data leave open as identify adds it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from planning_cases import RANGES_DEG, SHOULDER_YZ_M, nominal_arm

from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.pipeline import IdentifyOptions, identify_recordings
from bsp_ros.core.planning import JointLimits, Plan, PlanRequest, plan_protocol
from bsp_ros.core.planning.choice import ScoreCovariance, expected_choice_variance
from bsp_ros.core.planning.compare import compare_budget_with_estimate
from bsp_ros.core.planning.simulated import nominal_subject, plan_passive_truth, simulated_recordings
from bsp_ros.core.streams import segments_for

# Markers re-placed uniformly within +-b per axis: sd b / sqrt(3), identify's assumed 2 mm.
SKIN_BOUND_M = 0.002 * math.sqrt(3.0)


@pytest.fixture(scope="module")
def auto_plan() -> Plan:
    request = PlanRequest(
        nominal=nominal_arm(),
        shoulder_yz_m=SHOULDER_YZ_M,
        limits=JointLimits(RANGES_DEG),
        passive=PassiveModel.parse("auto"),
        n_points=1,
    )
    return plan_protocol(request)


def test_the_nominal_subject_has_the_nominal_static_moments() -> None:
    nominal = nominal_arm()
    subject = nominal_subject(nominal)
    assert subject.lengths_m == pytest.approx(nominal.lengths_m)
    assert subject.static_moments_kgm == pytest.approx(nominal.static_moments_kgm, rel=1e-12)
    # The table's own masses come back: the nominal arm is the table arm of its lengths.
    table = [segment_norm.mass_fraction * 75.0 for segment_norm in _norms(len(nominal.lengths_m))]
    assert subject.masses_kg == pytest.approx(table, rel=1e-9)


def _norms(n: int) -> list:
    from bsp_ros.core.anthropometry import segment_norm

    return [segment_norm("male", name) for name in segments_for(n)]


def test_the_plan_predicts_for_the_model_identify_chooses_on_another_session(auto_plan: Plan) -> None:
    choice = auto_plan.auto_choice
    assert choice is not None and auto_plan.budget is not None
    assert choice.chosen != PassiveModel.parse("auto").candidates()[-1]  # not the richest any more
    # Another session of the same arm (another noise and marker placement, untared) identified as bsp identify does
    # (seed 13: seeds 11 and 12 of this plan are invalid, an elastic effect the chosen model lacks).
    subject = nominal_subject(auto_plan.request.nominal)
    truth = plan_passive_truth(auto_plan)
    sessions = [c.session for c in simulated_recordings(auto_plan, subject, truth, 13, SKIN_BOUND_M)]
    estimate = identify_recordings(sessions, IdentifyOptions(passive=auto_plan.request.passive))
    assert estimate["quality"]["valid"]
    assert estimate["diagnostics"]["passive_model"] == choice.chosen.label
    rows = compare_budget_with_estimate(auto_plan.budget, estimate)
    assert len(rows) == len(auto_plan.budget.names) == 12  # the chosen model's parameters, not the richest's 24
    for row in rows:
        if row["quantity"] == "coulomb_nm":  # the marker placement's, the same whatever the choice
            assert 1 / 1.5 < row["ratio"] < 1.5, row
        else:
            # One session's model-choice term is one draw of the spread the plan predicts the expectation of
            # (0.2-1.9 times it over seeds of the bench's plan): the reported std varies that much between sessions.
            assert 1 / 3 < row["ratio"] < 3, row


def test_the_expected_choice_variance_is_that_of_repeated_least_squares_fits() -> None:
    """Against an independent implementation: ordinary least-squares fits of a nested pair of models (3 and 5
    columns) on many draws of white noise; identify's term is the largest over the open models (here the single
    richer one) of the squared difference or, where larger, the richer fit's variance beyond the chosen one's."""
    rng = np.random.default_rng(5)
    n_rows, sigma = 400, 0.3
    x = rng.standard_normal((n_rows, 5)) + 0.6 * rng.standard_normal((n_rows, 1))  # correlated columns
    names = [(f"p{k}", "j") for k in range(5)]
    design = x.T @ x / sigma**2
    scores = ScoreCovariance(names=names, design=design, noise=design, total=design)
    predicted = expected_choice_variance(scores, names[:3], [(names, False)], draws=20000, seed=1)
    # Nested fits of white noise: the difference's variance is the difference of the variances (Hausman).
    excess = np.diag(np.linalg.inv(design))[:3] - np.diag(np.linalg.inv(design[:3, :3]))
    squared, floored = np.zeros(3), np.zeros(3)
    draws = 3000
    for _ in range(draws):
        y = x @ np.array([1.0, -0.5, 0.2, 0.0, 0.0]) + sigma * rng.standard_normal(n_rows)
        small = np.linalg.lstsq(x[:, :3], y, rcond=None)[0]
        large = np.linalg.lstsq(x, y, rcond=None)[0]
        squared += (large[:3] - small) ** 2 / draws
        floored += np.maximum((large[:3] - small) ** 2, excess) / draws
    assert squared == pytest.approx(excess, rel=0.08)
    assert predicted == pytest.approx(floored, rel=0.08)


def test_re_placed_markers_do_not_read_as_an_open_model_s_noise(auto_plan: Plan) -> None:
    # An open model's variance beyond the chosen fit's is judged on the residual the markers' offsets leave, as the
    # chosen fit's own noise is: its raw residual holds what the offsets bend the torques by, which the placement
    # share counts already (a nonlinear model's wrist offset read 0.17 Nm of noise with the markers re-placed by
    # 2 mm, 0.02 with them on their centres).
    subject = nominal_subject(auto_plan.request.nominal)
    truth = plan_passive_truth(auto_plan)
    choice_nm = []
    for bound_m in (0.0, SKIN_BOUND_M):
        sessions = [c.session for c in simulated_recordings(auto_plan, subject, truth, 1, bound_m)]
        estimate = identify_recordings(sessions, IdentifyOptions(passive=auto_plan.request.passive))
        assert estimate["quality"]["valid"]
        choice_nm.append(estimate["joints"]["wrist"]["offset_nm"]["budget"]["model_choice"])
    assert choice_nm[1] < 2.0 * choice_nm[0], choice_nm
