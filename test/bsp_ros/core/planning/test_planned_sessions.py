"""Identification on planned sessions: offsets and stiffness separated from gravity; the paper's protocol is not."""

from __future__ import annotations

import numpy as np
import pytest
from planning_cases import ELASTIC_TRUTH

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.planning import Plan, compare_with_result, compare_with_scatter
from bsp_ros.core.planning.information import predict_covariance

ELASTIC_MODEL = PassiveModel.parse("coulomb+offset+stiffness")


# The simulated markers sit on the joint centres: no placement uncertainty.
EXACT_MARKERS = JointConfig(passive=ELASTIC_MODEL, marker_placement_sd_m=0.0)
# The model `bsp plan` predicts the std of (quasi-static, exact markers), on the arm it assumes.
AS_PLANNED = JointConfig(passive=ELASTIC_MODEL, marker_placement_sd_m=0.0, dynamics=False)


def _identify(
    trajectory: object, seed: int, passive: sim.PassiveTruth = ELASTIC_TRUTH, config: JointConfig = EXACT_MARKERS
) -> tuple[IdentificationResult, dict]:
    inertia = config.dynamics
    cell = sim.human_arm_cell(seed=seed, passive=passive, trajectory=trajectory, inertia=inertia)
    session = sim.simulate_cell(cell)
    result = identify_joint(identification_data_from_session(session.session), config)
    return result, session.truth.to_dict()


def _truth(truth: dict, key: str, owner: str) -> float:
    return float(truth["segments" if owner in truth["segments"] else "joints"][owner][key])


@pytest.fixture(scope="module")
def planned_result(plan: Plan) -> tuple[IdentificationResult, dict]:
    return _identify(plan.trajectory, seed=3)


def test_planned_session_is_valid(planned_result) -> None:
    result, _ = planned_result
    assert result.valid, result.message


def test_planned_session_static_moments_within_one_percent(planned_result) -> None:
    result, truth = planned_result
    for segment in ("upper_arm", "forearm", "hand"):
        value = result.value("static_moment_kgm", segment)
        assert value == pytest.approx(_truth(truth, "static_moment_kgm", segment), rel=0.01), segment


def test_planned_session_offsets_and_elbow_stiffness_within_ten_percent(planned_result) -> None:
    result, truth = planned_result
    for joint in ("shoulder", "elbow", "wrist"):
        assert result.value("offset_nm", joint) == pytest.approx(0.2, rel=0.10), joint
    assert result.value("stiffness_nm_per_rad", "elbow") == pytest.approx(1.5, rel=0.10)
    assert _truth(truth, "offset_nm", "elbow") == 0.2


def test_planned_session_truth_within_three_std(planned_result) -> None:
    result, truth = planned_result
    for (key, owner), value, std in zip(result.names, result.values, result.std, strict=True):
        assert abs(value - _truth(truth, key, owner)) < 3 * std, (key, owner, value, std)


def test_planned_session_is_not_flagged_confounded(planned_result) -> None:
    # Offsets and stiffness still correlate with gravity above 0.95 on a planned session, but the session
    # pins the static moments down to well under 1 %: nothing is confounded.
    result, _ = planned_result
    assert FindingCode.CONFOUNDED not in [f.code for f in result.findings], result.warnings


def test_paper_protocol_with_the_same_truth_is_flagged_confounded() -> None:
    result, truth = _identify(sim.human_arm_cell().trajectory, seed=3)
    confounded = [f for f in result.findings if f.code is FindingCode.CONFOUNDED]
    assert confounded, result.warnings
    assert result.weak or not result.valid
    # flagged, and not valid-and-wrong: every estimate is within 3 of its (large) std
    for (key, owner), value, std in zip(result.names, result.values, result.std, strict=True):
        assert abs(value - _truth(truth, key, owner)) < 3 * std, (key, owner, value, std)


def test_wrist_coulomb_within_five_percent_with_wrist_range_five_degrees(wrist_limited_plan: Plan) -> None:
    low, high = (np.degrees(v[2]) for v in wrist_limited_plan.trajectory.range_rad)
    assert -5.0 - 1e-9 <= low and high <= 5.0 + 1e-9
    result, _ = _identify(wrist_limited_plan.trajectory, seed=4)
    assert result.valid, result.message
    assert result.value("coulomb_nm", "wrist") == pytest.approx(0.06, rel=0.05)


def test_predicted_std_matches_the_reported_std(plan: Plan) -> None:
    result, _ = _identify(plan.trajectory, seed=3, config=AS_PLANNED)
    for row in compare_with_result(plan.prediction, result):
        assert 1 / 1.5 < float(row["ratio"]) < 1.5, row


def test_predicted_std_matches_the_scatter_of_eight_sessions(plan: Plan) -> None:
    # Stiffness at every joint keeps all estimates off their bounds (a bound truncates the scatter). Eight
    # sessions estimate a std to about +-25 %, hence factor 2 here; scripts/plan_std_sweep.py runs 20 for 1.5.
    passive = sim.PassiveTruth(
        coulomb_nm=(0.5, 0.28, 0.06), offset_nm=(0.2, 0.2, 0.2), stiffness_nm_per_rad=(1.0, 1.5, 0.2)
    )
    results = [_identify(plan.trajectory, seed, passive, AS_PLANNED)[0] for seed in range(8)]
    for row in compare_with_scatter(plan.prediction, results):
        assert 0.5 < float(row["ratio"]) < 2.0, row


def test_predicted_std_matches_the_reported_std_with_every_elastic_term(plan: Plan) -> None:
    # The model `bsp plan --passive auto` predicts for: the richest of the family, nonlinear and two-joint
    # coupling terms with the estimator's priors. Static moments are what the plan's warning is judged on.
    richest = PassiveModel.parse("auto").candidates()[-1]
    request = plan.request
    prediction = predict_covariance(plan.trajectory, request.duration_s, request.nominal, richest, request.noise)
    config = JointConfig(passive=richest, marker_placement_sd_m=0.0, dynamics=False)
    result, _ = _identify(plan.trajectory, seed=3, config=config)
    rows = compare_with_result(prediction, result)
    assert len(rows) == len(result.names) > 20
    identified = 0
    for row in rows:
        if row["quantity"] != "static_moment_kgm":
            continue
        predicted, value = float(row["predicted_std"]), abs(float(row["value"]))
        if predicted < 0.5 * value:
            assert 1 / 1.5 < float(row["ratio"]) < 1.5, row
            identified += 1
        else:
            # Left open by one posture (the upper arm here, 270 % predicted): the size of so wide a std hangs on
            # the shape probe's fit, within a factor 2.5 of the prediction; both must call it not identified.
            assert float(row["ratio"]) * predicted > 0.5 * value, row
            assert 1 / 2.5 < float(row["ratio"]) < 2.5, row
    assert identified == 2


def test_the_predicted_std_of_a_confounded_design_is_the_estimators() -> None:
    """The paper's protocol (one posture, narrow ranges) with every elastic term: the upper arm's static moment is
    confounded with the passive curves. The planner inverted its normal equations unscaled, and the pseudo-inverse
    dropped that direction: predicted 0.72 kg m where the estimator reports 25.5 (35 times)."""
    from bsp_ros.core.planning import NoiseSpec, NominalArm

    richest = PassiveModel.parse("auto").candidates()[-1]
    cell = sim.human_arm_cell(seed=3, inertia=False)
    nominal = NominalArm.from_anthropometry(list(cell.subject.lengths_m))
    prediction = predict_covariance(cell.trajectory, cell.duration_s, nominal, richest, NoiseSpec())
    config = JointConfig(passive=richest, marker_placement_sd_m=0.0, dynamics=False)
    result = identify_joint(identification_data_from_session(sim.simulate_cell(cell).session), config)
    rows = [row for row in compare_with_result(prediction, result) if row["quantity"] == "static_moment_kgm"]
    assert len(rows) == 3
    for row in rows:
        assert 1 / 1.5 < float(row["ratio"]) < 1.5, row
    (upper,) = [row for row in rows if row["owner"] == "upper_arm"]
    assert float(upper["predicted_std"]) > 10 * abs(float(upper["value"]))  # not identifiable, and said so
