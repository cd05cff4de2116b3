"""The report's line per joint that resisted a fast stretch more than a slow one, from a real two-speed split."""

from __future__ import annotations

import dataclasses
import html
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.clinic.histories import Patient, session_estimate
from bsp_ros.clinic.report import analyse, render_report
from bsp_ros.clinic.report.speed_lines import speed_dependence_line
from bsp_ros.clinic.store import SubjectRecord, open_store
from bsp_ros.core import simulation as sim
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.planning.two_speed import TwoSpeedPath

PATIENT = Patient("female", 68.0, 1.65, (0.5, 0.28, 0.06), (0.0, 1.5, 0.0))


def two_speed_notes(reflex_gain_nm_s_per_rad: float) -> list[Finding]:
    """The ``speed_dependent_resistance`` notes of a simulated 60 s two-speed session (the paper's sines, then four
    times faster) whose elbow resists extension faster than 0.02 rad/s with ``reflex_gain`` (0: a relaxed arm)."""
    path = TwoSpeedPath(sim.human_arm_cell().trajectory, (1.0, 4.0), 30.0, 60.0)
    session = sim.simulate_cell(sim.human_arm_cell(seed=3, duration_s=60.0, trajectory=path))
    data = identification_data_from_session(session.session)
    tau = data.tau_nm.copy()
    tau[:, 1] -= reflex_gain_nm_s_per_rad * np.clip(-data.velocity_rad_s[:, 1] - 0.02, 0.0, None)
    result = identify_joint(dataclasses.replace(data, tau_nm=tau), JointConfig(marker_placement_sd_m=0.0))
    return [f for f in result.findings if f.code is FindingCode.SPEED_DEPENDENT_RESISTANCE]


def report_page(tmp_path: Path, notes: list[Finding]) -> str:
    """The report of one stored session carrying ``notes``."""
    estimate = Estimate.from_json(session_estimate(PATIENT, 0, 7)).with_findings(*notes)
    with open_store(tmp_path / "clinic.sqlite") as store:
        store.set_subject(SubjectRecord("S101", 68.0, 1.65, "female", "left", "left"))
        store.add_estimate(estimate, "S101")
        analysis = analyse("S101", store.sessions("S101"), subject_record=store.subject_record("S101"))
    return html.unescape(render_report(analysis))


def test_a_joint_that_resists_a_fast_stretch_more_has_its_line_in_the_report(tmp_path: Path) -> None:
    notes = two_speed_notes(4.0)
    elbow = next(f for f in notes if f.where == "elbow")
    part, std = elbow.values["part_nm"], elbow.values["std_nm"]
    assert part > 3 * std
    expected = (
        f"Elbow: resistance to a fast stretch {part:.2g} +- {std:.1g} Nm more than to a slow one (possible spasticity)"
    )
    assert speed_dependence_line(elbow) == expected
    page = report_page(tmp_path, notes)
    assert f"Session 1: {expected}." in page
    assert page.count("resistance to a fast stretch") == 1  # the wrist, also at two speeds, showed none


def test_a_relaxed_arm_at_two_speeds_has_no_such_line(tmp_path: Path) -> None:
    notes = two_speed_notes(0.0)
    assert {f.where for f in notes} >= {"elbow"} and not any(f.values["exceeds"] for f in notes)
    assert all(speed_dependence_line(f) is None for f in notes)
    assert "resistance to a fast stretch" not in report_page(tmp_path, notes)


@pytest.mark.parametrize("code", [FindingCode.SPASTICITY, FindingCode.ARM_ACTIVE])
def test_other_findings_give_no_speed_line(code: FindingCode) -> None:
    assert speed_dependence_line(Finding(code=code, where="elbow")) is None
