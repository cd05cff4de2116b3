"""What a live session is for: a `bsp plan` JSON's predicted stds (``plan_file``) or named parameters, passive ones
included (``target_parameters``), as bsp_identifier's parameters give them; bad values refused naming the parameter.
Checked against a plan written by `bsp plan` and the estimate of a simulated session (its std computed here)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from bsp_ros.cli import main
from bsp_ros.core import simulation as sim
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.errors import InputError
from bsp_ros.live.online.identifier_settings import IdentifierSettings
from bsp_ros.live.online.precision import PrecisionTracker

PLAN_S = 30.0


@pytest.fixture(scope="module")
def plan(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """A 30 s plan of `bsp plan` (the cell guide's ranges) and its JSON."""
    path = tmp_path_factory.mktemp("plan") / "plan.json"
    ranges = ["--shoulder-range", "-70", "-10", "--elbow-range", "10", "100", "--wrist-range", "-20", "20"]
    argv = ["plan", "--shoulder", "0", "1.2", *ranges, "--duration", str(PLAN_S), "--json", str(path)]
    assert main(argv) == 0
    return path, json.loads(path.read_text())


def test_a_plan_gives_each_static_moment_the_relative_std_it_predicts(plan: tuple[Path, dict[str, Any]]) -> None:
    path, document = plan
    settings = IdentifierSettings.from_parameters({"plan_file": str(path), "precision_hold_s": 3.0})
    target = settings.precision_target
    assert target is not None and target.hold_s == 3.0
    predicted = {
        (row["owner"], row["quantity"]): row["relative_std"]
        for row in document["predicted"]
        if row["quantity"] == "static_moment_kgm"
    }
    assert set(predicted) == {(s, "static_moment_kgm") for s in ("upper_arm", "forearm", "hand")}
    assert target.relative_std == predicted  # the passive terms have no nominal value: no relative std to reach
    # The recursive mode holds the whole session: any plan length.
    longer = IdentifierSettings.from_parameters({"plan_file": str(path), "mode": "recursive", "window_s": 10.0})
    assert longer.precision_target is not None and longer.precision_target.relative_std == predicted


@pytest.mark.parametrize(
    ("values", "named"),
    [
        ({"window_s": 20.0}, "set window_s to 30 or more"),  # the window holds less than the plan's session
        ({"target_std_percent": 5.0}, "leave target_std_percent at 0"),
        ({"target_parameters": "elbow.coulomb_nm"}, "target_parameters empty"),
        ({"n_segments": 2}, "is for the segments ['upper_arm', 'forearm', 'hand']"),
    ],
)
def test_a_plan_that_does_not_fit_the_identifier_is_refused_naming_the_parameter(
    plan: tuple[Path, dict[str, Any]], values: dict[str, Any], named: str
) -> None:
    path, _ = plan
    with pytest.raises(InputError, match="parameter plan_file") as refused:
        IdentifierSettings.from_parameters({"plan_file": str(path), **values})
    assert named in str(refused.value) and len(str(refused.value).splitlines()) == 1


def test_a_file_that_is_not_a_plan_is_refused(tmp_path: Path) -> None:
    (tmp_path / "estimate.json").write_text(json.dumps({"schema": "bsp_ros/core/estimate/1"}))
    for path, named in ((tmp_path / "none.json", "cannot read the plan"), (tmp_path / "estimate.json", "not a")):
        with pytest.raises(InputError, match="parameter plan_file") as refused:
            IdentifierSettings.from_parameters({"plan_file": str(path)})
        assert named in str(refused.value)


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ("shoulder_blade.coulomb_nm", "names no segment or joint"),
        ("forearm.coulomb_nm", "forearm has no 'coulomb_nm'"),
        ("elbow.stiffness_nm_per_rad", "elbow has no 'stiffness_nm_per_rad'"),  # not in the Coulomb model
        ("forearm", "forearm has no ''"),
    ],
)
def test_target_parameters_outside_the_estimate_are_refused(text: str, named: str) -> None:
    with pytest.raises(InputError, match="parameter target_parameters") as refused:
        IdentifierSettings.from_parameters({"target_std_percent": 10.0, "target_parameters": text})
    assert named in str(refused.value)


def test_named_parameters_passive_ones_included_are_tracked_on_a_real_estimate() -> None:
    values = {"target_std_percent": 30.0, "target_parameters": "forearm.static_moment_kgm, elbow.coulomb_nm"}
    target = IdentifierSettings.from_parameters(values).precision_target
    assert target is not None
    assert target.relative_std == {("forearm", "static_moment_kgm"): 0.3, ("elbow", "coulomb_nm"): 0.3}
    with_stiffness = {
        **values,
        "passive": "coulomb+offset+stiffness",
        "target_parameters": "elbow.stiffness_nm_per_rad",
    }
    assert IdentifierSettings.from_parameters(with_stiffness).precision_target is not None
    # The std the tracker reads is the estimate's own, the joint's as the segment's.
    simulated = sim.simulate_cell(sim.human_arm_cell(seed=21, duration_s=40.0))
    document = identify_session(simulated.session, IdentifyOptions())
    assert document["quality"]["valid"]
    state = PrecisionTracker(target).update(Estimate.from_json(document), 0)
    for parameter in state.parameters:
        group = "segments" if parameter.owner == "forearm" else "joints"
        q = document[group][parameter.owner][parameter.quantity]
        assert parameter.relative_std == pytest.approx(q["std"] / abs(q["value"]))
        assert parameter.within == (q["std"] / abs(q["value"]) <= 0.3)
