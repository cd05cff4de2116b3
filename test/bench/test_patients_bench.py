"""bench/patients.py's scoring: the four outcomes, the cause-naming rate and false alarms on hand-made estimates."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("mujoco", reason="bench/patients.py builds MuJoCo cells")

# The benchmarks are scripts, not a package: their directory is put on the path as they run it.
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

import patients

TRUTH = {"segments": {"forearm": {"static_moment_kgm": 0.25}}, "joints": {}, "patient": {"activity": {}}}


def _estimate(value: float, valid: bool, *codes: tuple[str, str]) -> dict[str, Any]:
    return {
        "segments": {"forearm": {"static_moment_kgm": {"value": value, "std": 0.01, "source": "data"}}},
        "joints": {},
        "quality": {"valid": valid, "findings": [{"code": c, "severity": s} for c, s in codes]},
    }


def test_every_case_has_its_causes_and_only_the_controls_have_none() -> None:
    names = [case.name for case in patients.cases()]
    assert names == list(patients.CAUSES)
    assert {n for n, causes in patients.CAUSES.items() if not causes} == {n for n in names if n.startswith("control")}
    assert all(
        causes <= patients.PATIENT_CODES | {"placement_wider", "friction_speed_dependent"}
        for causes in patients.CAUSES.values()
    )


def test_outcomes_and_the_cause_naming_rate_count_what_the_estimates_say() -> None:
    causes = patients.CAUSES["activity_5"]
    tally = patients.Tally()
    tally.add(_estimate(0.251, True, ("prior_note", "note")), TRUTH, causes)  # right, silent: not flagged
    tally.add(_estimate(0.29, True, ("arm_active", "note")), TRUTH, causes)  # 4 std off: valid and wrong, named
    tally.add(_estimate(0.25, False, ("model_misfit", "invalid")), TRUTH, causes)  # invalid, right, cause unnamed
    tally.add(_estimate(0.20, False, ("too_little_relaxed", "invalid")), TRUTH, causes)  # invalid, wrong, named
    assert (tally.valid_right, tally.valid_wrong, tally.invalid_right, tally.invalid_wrong) == (1, 1, 1, 1)
    assert (tally.flagged, tally.named) == (3, 2)
    assert tally.naming() == "2/3  67%"
    assert tally.worst_param == "static_moment_kgm/forearm" and tally.worst_z == pytest.approx(5.0)


def test_a_run_without_a_cause_counts_as_a_false_alarm_when_it_names_one() -> None:
    quiet = {**TRUTH, "patient": {"spasticity": {"active_fraction": 0.0}}}
    assert not patients.cause_imposed(quiet)
    assert patients.cause_imposed({**TRUTH, "patient": {"spasticity": {"active_fraction": 0.1}}})
    tally = patients.Tally()
    tally.add(_estimate(0.25, True, ("spasticity", "note")), quiet, frozenset())
    tally.add(_estimate(0.25, True), quiet, frozenset())
    assert tally.naming() == "false 1/2"
