"""Typed findings: the table is total, texts render from codes, the verdict derives from severities, JSON round-trips,
and every code is asserted by some test of the estimator or its consumers."""

from __future__ import annotations

import datetime
import json
import re
from html import escape
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.clinic.report import analyse
from bsp_ros.clinic.report.html import render_html
from bsp_ros.clinic.report.labels import PART_NAMES
from bsp_ros.clinic.report.speed_lines import speed_dependence_lines
from bsp_ros.clinic.report.summary import invalid_cause, session_notes, technical_notes
from bsp_ros.clinic.store.records import Quality, SessionRecord
from bsp_ros.core.estimate_schema import Estimate, Level
from bsp_ros.core.estimate_schema import Quality as EstimateQuality
from bsp_ros.core.findings import Finding, FindingCode, Severity, findings_of, note
from bsp_ros.core.findings_specs import SPECS
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.methods import Method

TEST_ROOT = Path(__file__).resolve().parents[2]

# Values that render every code (the units its keys name).
SAMPLE_VALUES: dict[FindingCode, dict[str, object]] = {
    FindingCode.TOO_FEW_SAMPLES: {"n": 198, "min_samples": 200},
    FindingCode.TOO_FEW_USABLE_SAMPLES: {"fewest": 3},
    FindingCode.NO_MOTION: {"range_deg": 0.01, "min_range_deg": 2.0},
    FindingCode.ONE_DIRECTION: {"other_percent": 1.5},
    FindingCode.DIRECTION_UNCLEAR: {"share_percent": 4.0},
    FindingCode.NOT_IDENTIFIABLE: {"condition": 3e9},
    FindingCode.FAR_OFF_SAMPLES: {"n_far": 900, "usable": 4000, "outlier_sd": 8.0},
    FindingCode.HANGS_ON_FEW_SAMPLES: {"n_far": 12, "key": "coulomb_nm", "shift_sd": 2.5},
    FindingCode.TOO_LITTLE_RELAXED: {"relaxed_s": 21.0, "relaxed_percent": 35.0, "n_stretches": 9},
    FindingCode.HAND_SLIPPED: {"slip_mm": 8.2, "trend_percent": 91.0, "left_out_s": 4.5},
    FindingCode.SPASTICITY: {"increase_nm": 0.08, "fast_rad_s": 0.04, "direction": -1},
    FindingCode.TREMOR: {"frequency_hz": 5.1, "torque_nm": 0.21, "angle_deg": 0.02},
    FindingCode.TREMOR_FRICTION: {"angle_deg": 0.3, "frequency_hz": 5.1, "speed_percent": 80.0},
    FindingCode.ARM_ACTIVE: {"n_stretches": 3, "active_s": 6.5, "active_percent": 10.8, "peak_nm": 1.2},
    FindingCode.MODEL_MISFIT: {"rms_nm": 0.186, "ratio": 5.8, "noise_nm": 0.032},
    FindingCode.PERPENDICULAR_IMPLAUSIBLE: {"prior_sd_off": 7.5, "value_kgm": 0.05, "family_chosen": False},
    FindingCode.STATIC_MOMENT_IMPLAUSIBLE: {"value_kgm": 3.0, "typical_kgm": 0.3, "factor": 3.0},
    FindingCode.ROTATION_ASSUMED: {"frame": "ft_sensor"},
    FindingCode.ROTATION_FROM_MOUNTING: {
        "world": "world",
        "frame": "ft_sensor",
        "source": "topic /ft_sensor/transform (TransformStamped)",
        "tf_wait_s": 2.0,
        "stated": "wrench_frame_rotation_xyzw (cell file cell.yaml: ft_sensor.rotation_xyzw)",
        "rotation_xyzw": [0.965926, 0.258819, 0.0, 0.0],
    },
    FindingCode.ROTATION_DISAGREES: {
        "world": "world",
        "frame": "ft_sensor",
        "source": "tf (/tf_static, /tf)",
        "received_xyzw": [0.939693, 0.34202, 0.0, 0.0],
        "angle_deg": 10.0,
        "limit_deg": 1.0,
        "stated": "wrench_frame_rotation_xyzw (cell file cell.yaml: ft_sensor.rotation_xyzw)",
        "stated_xyzw": [0.965926, 0.258819, 0.0, 0.0],
    },
    FindingCode.INPUT_WAITING: {"what": "wrench"},
    FindingCode.INPUT_STALE: {"what": "wrench", "silent_s": 0.52},
    FindingCode.INTERNAL_ERROR: {"error": "ValueError('x')"},
    FindingCode.INPUT_UNUSABLE: {"detail": "no wrench sample in the window has joint angles"},
    FindingCode.WINDOW_WITHOUT_STD: {"key": "coulomb_nm"},
    FindingCode.CONFOUNDED: {"key": "coulomb_nm", "corr": 0.97, "segment": "forearm", "rel_std": 0.31},
    FindingCode.UNCERTAIN_STATIC_MOMENT: {"value_kgm": 0.02, "std_kgm": 0.015},
    FindingCode.ELASTIC_TERM: {
        "kinds": "offset and stiffness",
        "chi2": 85.0,
        "corr": 0.93,
        "segment": "forearm",
        "change_percent": 12.0,
        "shift_sd": 4.1,
        "fallback": True,
    },
    FindingCode.DIRECTION_NOISY: {"noise_rad_s": 0.01, "typical_rad_s": 0.012},
    FindingCode.FRICTION_SMOOTH: {"width_mrad_s": 3.0, "beyond_percent": 80.0},
    FindingCode.FRICTION_TRANSITION_WEAK: {"beyond_percent": 2.0},
    FindingCode.FIT_OUTLIERS_REMOVED: {"n": 3, "outlier_sd": 8.0, "near_gap": 2, "gap_edge_s": 0.25},
    FindingCode.WRENCH_SPIKES_REMOVED: {"n": 1, "outlier_sd": 8.0, "window": 11},
    FindingCode.MODEL_CHOICE_SPREAD: {"shift_sd": 1.2},
    FindingCode.DRIFT_MODELLED: {
        "drift_recording": 0,
        "rate_mn_s": 4.0,
        "amount_n": 0.16,
        "span_s": 40.0,
        "segment": "upper_arm",
        "shift_sd": 3.2,
    },
    FindingCode.POORLY_EXCITED: {"condition": 2e4, "max_condition": 1e4},
    FindingCode.STATIC_MOMENT_OPEN: {"own_kgm": -0.01},
    FindingCode.PARAMETER_AT_BOUND: {"key": "coulomb_nm", "lower": 0.0},
    FindingCode.FRICTION_SPEED_DEPENDENT: {
        "speed_mrad_s": 10.0,
        "moves": "coulomb_in_std",
        "segment": "forearm",
        "shift_sd": 0.4,
        "coulomb_shift_nm": -0.02,
        "coulomb_sd": 0.8,
    },
    FindingCode.PLACEMENT_WIDER: {"assumed_mm": 2.0, "apparent_mm": 6.0, "at_limit": False},
    FindingCode.GRIP_COMPLIANT: {"stick_s": 3.2, "stuck_percent": 38.0, "dwell_ratio": 4.4, "n_joints": 2},
    FindingCode.SPEED_DEPENDENT_RESISTANCE: {
        **{"part_nm": 0.034, "std_nm": 0.003, "direction": -1, "slow_rad_s": 0.0095, "fast_rad_s": 0.038},
        **{"exceeds": True, "static_from_slow": True, "positive_nm": 0.0, "positive_std_nm": 0.002},
        **{"negative_nm": 0.034, "negative_std_nm": 0.003},
    },
    FindingCode.ELASTIC_FAMILY_CHOSEN: {
        "model": "coulomb",
        "joints": ["wrist"],
        "rms_nm": [0.05],
        "ratio": [6.1],
        "noise_nm": [0.008],
    },
    FindingCode.FUSION_FAILED: {"error": "singular matrix"},
    FindingCode.BAG_DAMAGED: {"crc_errors": 2, "truncated": True, "lost_messages": None},
    FindingCode.BAG_POSSIBLY_DAMAGED: {"implausible": [["wrench_absurd", 3]]},
}
for _code in (
    FindingCode.DATA_NOTE,
    FindingCode.BAG_NOTE,
    FindingCode.TIMING_NOTE,
    FindingCode.TARE_NOTE,
    FindingCode.PRIOR_NOTE,
):
    SAMPLE_VALUES[_code] = {"detail": "a note written below the estimator"}


def sample(code: FindingCode, where: str = "elbow") -> Finding:
    """A finding of ``code`` with :data:`SAMPLE_VALUES`."""
    return Finding(code=code, where=where, values=SAMPLE_VALUES.get(code, {}))


@pytest.mark.parametrize("code", list(FindingCode))
def test_every_code_renders_a_sentence_and_round_trips_through_json(code: FindingCode) -> None:
    finding = sample(code)
    text = finding.text
    assert text and "{" not in text and "None" not in text.replace("None)", ""), text
    back = Finding.from_json(finding.to_json())
    assert back.code is code and back.text == text and back.severity is SPECS[code].severity


def test_texts_are_rendered_from_the_values() -> None:
    assert sample(FindingCode.TOO_FEW_SAMPLES).text == "too few samples: 198 < 200"
    assert Finding(code=FindingCode.TOO_FEW_SAMPLES, values={"updates": 37}).text == "too few samples: 37 updates"
    assert sample(FindingCode.NO_MOTION, "wrist").text == "no motion at the wrist: range 0.010 deg < 2.0 deg"
    assert Finding(code=FindingCode.ONE_DIRECTION).text == "each joint must move both ways"
    removed = Finding(code=FindingCode.FIT_OUTLIERS_REMOVED, values={"n": 1, "outlier_sd": 8.0})
    assert removed.text == "removed 1 sample far off the fit (residual over 8 robust sd)"
    assert sample(FindingCode.BAG_NOTE).in_recording(2).text == "recording 2: a note written below the estimator"


def test_validity_weakness_and_message_derive_from_the_findings() -> None:
    names = [("static_moment_kgm", "upper_arm")]
    base = IdentificationResult(method="joint", names=names, values=np.ones(1), covariance=np.eye(1), summary="ok")
    assert base.valid and not base.weak and base.message == "ok" and base.warnings == []
    weak = base.with_findings(sample(FindingCode.CONFOUNDED), sample(FindingCode.DRIFT_MODELLED))
    assert weak.valid and weak.weak and weak.message == "ok" and len(weak.warnings) == 2
    invalid = weak.with_findings(sample(FindingCode.MODEL_MISFIT), sample(FindingCode.NO_MOTION))
    assert not invalid.valid and not invalid.weak
    assert invalid.message == f"{sample(FindingCode.MODEL_MISFIT).text}; {sample(FindingCode.NO_MOTION).text}"
    assert invalid.warnings == weak.warnings  # notes stay notes
    noted = base.with_findings(sample(FindingCode.POORLY_EXCITED))
    assert noted.valid and not noted.weak


def test_an_estimate_gains_findings_in_its_message_and_warnings() -> None:
    waiting = Estimate.invalid(Method.JOINT, Finding(code=FindingCode.INPUT_WAITING, values={"what": "markers"}))
    assert waiting.quality.message == "waiting for markers"
    assert [f.code for f in waiting.quality.findings] == [FindingCode.INPUT_WAITING]
    added = waiting.with_findings(note(FindingCode.BAG_NOTE, "first"), at=0)
    quality = added.with_findings(sample(FindingCode.ROTATION_ASSUMED)).quality
    assert quality.warnings == ("first",) and waiting.quality.warnings == ()  # a new estimate, the old one as it was
    assert quality.message.startswith("missing transform world -> ft_sensor") and "; waiting for markers" in (
        quality.message
    )
    assert [f.code for f in quality.findings] == [
        FindingCode.ROTATION_ASSUMED,
        FindingCode.INPUT_WAITING,
        FindingCode.BAG_NOTE,
    ]
    valid = EstimateQuality(valid=True, level=Level.OK, message="identified from 10 samples")
    judged = valid.with_finding(sample(FindingCode.STATIC_MOMENT_IMPLAUSIBLE, "forearm"))
    assert not judged.valid and judged.level is Level.INVALID and judged.message.startswith("implausible forearm")


def test_findings_of_skips_a_code_it_does_not_know() -> None:
    quality = {"findings": [{"code": "from_a_newer_version"}, sample(FindingCode.NO_MOTION).to_json()]}
    assert [f.code for f in findings_of(quality)] == [FindingCode.NO_MOTION]


def _stored(quality: Quality) -> SessionRecord:
    """A stored session of ``quality`` (the report reads its cause from it)."""
    return SessionRecord(
        subject="P001",
        session_time_ns=1_700_000_000_000_000_000,
        source="s.mcap",
        method="joint",
        config={},
        subject_info={},
        estimate_schema="bsp_ros/core/estimate/1",
        quality=quality,
        parameters={},
    )


@pytest.mark.parametrize("code", [c for c in FindingCode if SPECS[c].severity is Severity.INVALID])
def test_every_invalid_code_gives_the_report_a_cause_and_an_action(code: FindingCode) -> None:
    finding = sample(code, "elbow")
    cause, action = invalid_cause(_stored(Quality(valid=False, message=finding.text, findings=(finding,))))
    assert cause == SPECS[code].cause.format(where="elbow") and action == SPECS[code].action
    assert cause and action and "{" not in cause


CLINIC_CODES = [c for c in FindingCode if SPECS[c].severity is not Severity.INVALID and SPECS[c].cause]
"""The weak codes and the notes a clinic reads: each reaches the report's session notes with its cause and action."""
ENGINEER_CODES = [c for c in FindingCode if SPECS[c].severity is Severity.NOTE and not SPECS[c].cause]
"""The notes for the engineer only: the appendix's technical notes, never page 1 or the session notes."""


def _notes_of(*findings: Finding) -> list[str]:
    analysis = analyse("P001", [_stored(Quality(valid=True, findings=findings))])
    return [text for _, text in session_notes(analysis)]


def test_every_weak_code_is_for_the_clinic() -> None:
    weak = {c for c in FindingCode if SPECS[c].severity is Severity.WEAK}
    assert weak and weak <= set(CLINIC_CODES)


@pytest.mark.parametrize("code", CLINIC_CODES)
def test_every_weak_code_and_clinic_note_gives_the_session_notes_a_cause_and_an_action(code: FindingCode) -> None:
    spec = SPECS[code]
    assert spec.action, f"{code} has a cause but no action"
    where = PART_NAMES.get("elbow", "elbow").lower()
    expected = f"{spec.cause.format(where=where)}: {spec.action}"
    assert _notes_of(sample(code, "elbow")) == [expected[0].upper() + expected[1:]]


def test_engineer_only_notes_reach_the_appendix_and_never_page_1_or_the_session_notes() -> None:
    assert ENGINEER_CODES and all(not SPECS[c].action for c in ENGINEER_CODES)
    findings = tuple(sample(c) for c in ENGINEER_CODES)
    analysis = analyse("P001", [_stored(Quality(valid=True, findings=findings))])
    # A speed-dependent part beyond its noise reaches the notes as the report's own line, not as the note's text.
    assert session_notes(analysis) == speed_dependence_lines(analysis)
    texts = {text for _, text in technical_notes(analysis)}
    assert {f.text for f in findings} <= texts
    page = render_html(analysis, None, [], datetime.datetime(2026, 1, 1, tzinfo=datetime.UTC))
    first, detail = page.split("<section id='detail'>")
    assert not any(escape(f.text) in first for f in findings)
    assert all(escape(f.text) in detail for f in findings)


def test_a_session_stored_without_findings_gets_a_general_cause() -> None:
    record = _stored(Quality(valid=False, message="the model does not fit at the elbow"))
    assert invalid_cause(record) == ("the measurement could not be evaluated", "repeat the session")


def test_every_code_is_asserted_by_a_test() -> None:
    """Each code appears as ``FindingCode.<NAME>`` in a test other than this module's table."""
    used: set[str] = set()
    for path in TEST_ROOT.rglob("test_*.py"):
        if path.name == Path(__file__).name:
            continue
        used |= set(re.findall(r"FindingCode\.([A-Z_]+)", path.read_text(encoding="utf-8")))
    missing = sorted(c.name for c in FindingCode if c.name not in used)
    assert not missing, f"finding codes no test asserts: {missing}"


def test_the_contract_lists_every_code_under_its_severity() -> None:
    contract = (TEST_ROOT.parent / "docs" / "contract.md").read_text(encoding="utf-8")
    table = contract[contract.index("### Finding codes") :].split("\n\n")[2]
    listed: dict[str, Severity] = {}
    for row in table.splitlines()[2:]:
        severity, codes = row.strip("|").split("|")
        for code in re.findall(r"`([a-z_]+)`", codes):
            listed[code] = Severity(severity.strip().split(":")[0])
    assert listed == {str(c): SPECS[c].severity for c in FindingCode}


def test_a_value_json_cannot_hold_is_null_and_the_written_text_stays() -> None:
    values = {"key": "coulomb_nm", "corr": 0.99, "segment": "hand", "rel_std": float("inf")}
    confounded = Finding(code=FindingCode.CONFOUNDED, where="wrist", values=values)
    block = confounded.to_json()
    assert block["values"]["rel_std"] is None
    text = json.dumps(block, allow_nan=False)  # strict JSON, as every document is written
    back = Finding.from_json(json.loads(text))
    assert back.text == confounded.text and "inf" in back.text
