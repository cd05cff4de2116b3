"""`bsp plan`'s predicted std is the one `bsp identify` reports on a session that follows the plan, term by term."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import pytest
from planning_cases import RANGES_DEG, SHOULDER_YZ_M, nominal_arm

from bsp_ros.cli import main
from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.ledger import Term
from bsp_ros.core.pipeline import IdentifyOptions, identify_recordings
from bsp_ros.core.planning import JointLimits, Plan, PlanRequest, plan_protocol
from bsp_ros.core.planning.budget import SessionSpec
from bsp_ros.core.planning.compare import compare_budget_with_estimate
from bsp_ros.core.planning.simulated import plan_passive_truth, simulated_recordings

# Markers re-placed uniformly within +-b per axis: sd b / sqrt(3), identify's assumed 2 mm.
SKIN_BOUND_M = 0.002 * math.sqrt(3.0)


@pytest.fixture(scope="module")
def quick_plan() -> Plan:
    return plan_protocol(
        PlanRequest(
            nominal=nominal_arm(),
            shoulder_yz_m=SHOULDER_YZ_M,
            limits=JointLimits(RANGES_DEG),
            n_points=1,
            max_evaluations=60,
        )
    )


def _reported(plan: Plan, seed: int, options: IdentifyOptions) -> dict:
    """identify's estimate of one simulated session that follows ``plan`` (linear springs: within the model)."""
    subject = sim.SubjectTruth.from_anthropometry("male", 75.0, 1.78, 3)
    truth = dataclasses.replace(plan_passive_truth(plan), stiffening_nm=(0.0,) * 3, biarticular_nm=0.0)
    sessions = [cell.session for cell in simulated_recordings(plan, subject, truth, seed, SKIN_BOUND_M)]
    return identify_recordings(sessions, options)


def test_the_predicted_std_is_within_1_5x_of_the_reported_for_every_parameter(quick_plan: Plan) -> None:
    assert quick_plan.budget is not None
    estimate = _reported(quick_plan, seed=3, options=IdentifyOptions(passive=quick_plan.request.passive))
    assert estimate["quality"]["valid"]
    rows = compare_budget_with_estimate(quick_plan.budget, estimate)
    assert len(rows) == len(quick_plan.budget.names) == 12
    ratios = {f"{r['quantity']}/{r['owner']}": round(r["ratio"], 2) for r in rows}
    assert all(1 / 1.5 <= ratio <= 1.5 for ratio in ratios.values()), ratios
    # The largest term is named right where it dominates: the untared zero for the static moments of the
    # forearm and hand, the placement for the Coulomb amplitudes.
    largest = {f"{r['quantity']}/{r['owner']}": (r["predicted_largest"], r["reported_largest"]) for r in rows}
    for name in ("static_moment_kgm/forearm", "static_moment_kgm/hand"):
        assert largest[name] == ("sensor_zero", "sensor_zero")
    for joint in ("shoulder", "elbow", "wrist"):
        assert largest[f"coulomb_nm/{joint}"] == ("marker_placement", "marker_placement")


def test_the_information_matrix_alone_is_far_sharper_than_what_identify_reports(quick_plan: Plan) -> None:
    assert quick_plan.budget is not None
    i = quick_plan.budget.names.index(("static_moment_kgm", "forearm"))
    # The issue: the sensor-noise prediction alone was tens of times smaller than the std identify reports.
    assert quick_plan.budget.std[i] > 20 * quick_plan.prediction.std[i]
    sensor = quick_plan.budget.contributions(i)[Term.SENSOR_NOISE]
    assert sensor < 0.05 * quick_plan.budget.std[i]


def test_a_tared_session_keeps_only_the_tare_s_share_of_the_zero(quick_plan: Plan) -> None:
    request = dataclasses.replace(quick_plan.request, session=SessionSpec(tared=True))
    tared = plan_protocol(request)
    assert tared.budget is not None and quick_plan.budget is not None
    assert (tared.centres_deg == quick_plan.centres_deg).all()  # the same motion: only the std differs
    for i in range(3):
        zero = tared.budget.contributions(i)[Term.SENSOR_ZERO]
        assert zero < 0.01 * quick_plan.budget.contributions(i)[Term.SENSOR_ZERO]
        assert tared.budget.largest_term(i)[0] == Term.MARKER_PLACEMENT


def test_bsp_plan_prints_and_writes_the_budget(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "plan.json"
    argv = ["plan", "--shoulder", "0", "1.2", "--shoulder-range", "-70", "-10", "--elbow-range", "10", "100"]
    argv += ["--wrist-range", "-20", "20", "--operating-points", "1", "--max-evaluations", "40", "--passive", "coulomb"]
    assert main([*argv, "--json", str(out)]) == 0
    captured = capsys.readouterr()
    line = next(x for x in captured.out.splitlines() if x.startswith("static_moment_kgm/hand"))
    assert "sensor_zero" in line.split()
    # Placement and zero alone exceed 1 %: no duration is tried, and the warning says what would shrink them.
    assert "no session length reaches it" in captured.err and "a tare shrinks it" in captured.err
    plan = json.loads(out.read_text())
    assert plan["uncertainty"]["tared"] is False and plan["uncertainty"]["marker_placement_sd_m"] == 0.002
    rows = {f"{r['quantity']}/{r['owner']}": r for r in plan["predicted"]}
    hand = rows["static_moment_kgm/hand"]
    assert set(hand["budget"]) == {"sensor_noise", "marker_placement", "sensor_zero"}
    assert math.isclose(math.hypot(*hand["budget"].values()), hand["std"], rel_tol=1e-9)
