"""Report content: trends, change flags, priors, labels, exports, without a browser."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import pytest

from bsp_ros.cli import main
from bsp_ros.report import Point, analyse, flag_changes, label, unit
from bsp_ros.report.html import render_html
from bsp_ros.store import open_store
from bsp_ros.store.samples import SAMPLE_START_NS, sample_estimate

SUBJECT = "P007"  # as planted by the report_store fixture (conftest.py)
OTHER = "Q9other"


def _point(time_ns: int, value: float, std: float) -> Point:
    return Point(None, time_ns, value, std, "data", True, None)


def test_change_flag_threshold_is_three_combined_sigmas() -> None:
    key = ("joints", "elbow", "coulomb_nm")
    s = 0.1 / 3 / 2**0.5  # combined std of two sessions with std s: 3 * hypot(s, s) == 0.1
    just_inside = [_point(1, 1.0, s), _point(2, 1.0999, s)]
    just_outside = [_point(1, 1.0, s), _point(2, 1.1001, s)]
    assert flag_changes(key, just_inside) == []
    (change,) = flag_changes(key, just_outside)
    assert change.sigmas == pytest.approx(3.003, abs=1e-3)
    gap = [_point(1, 1.0, s), Point(None, 2, None, None, "data", False, None), _point(3, 0.5, s)]
    assert [c.after.time_ns for c in flag_changes(key, gap)] == [3]  # a missing value does not hide a change


def test_labels_are_plain_language() -> None:
    assert label(("joints", "elbow", "coulomb_nm")) == "Elbow friction (passive moment)"
    assert label(("segments", "forearm", "static_moment_kgm")).startswith("Forearm static moment")
    assert label(("segments", "upper_arm", "com_m")) == "Upper arm centre of mass (distance from the shoulder)"
    assert label(("joints", "wrist", "viscous_nms")) == "Wrist damping (passive moment per speed)"
    assert label(("joints", "knee", "backlash_rad")) == "Knee backlash"
    assert (unit("coulomb_nm"), unit("stiffness_nm_per_rad"), unit("backlash_rad")) == ("N·m", "N·m/rad", "rad")


def test_analysis_flags_the_planted_change_and_priors(report_store: str) -> None:
    with open_store(report_store) as store:
        analysis = analyse(SUBJECT, store.sessions(SUBJECT))
    assert len(analysis.sessions) == 6
    (change,) = analysis.changes
    assert change.key == ("joints", "elbow", "coulomb_nm") and change.delta > 0
    assert change.after.session_id == analysis.sessions[4].id
    mass = next(s for s in analysis.series if s.key == ("segments", "forearm", "mass_kg"))
    prior = mass.points[0].prior
    assert prior is not None and prior.mean == pytest.approx(75.0 * 0.0162)
    assert "de Leva" in analysis.prior_note


def test_no_prior_without_body_mass_and_sex_and_two_segments(tmp_path: Path) -> None:
    with open_store(tmp_path / "s.sqlite") as store:
        for i in range(3):
            estimate = sample_estimate(i, start_time_ns=SAMPLE_START_NS + i * 10**12, segments=("upper_arm", "forearm"))
            store.add_estimate(estimate, "arm2")
        analysis = analyse("arm2", store.sessions("arm2"))
    assert not any(s.has_prior for s in analysis.series)
    assert analysis.prior_note.startswith("No anthropometric reference band")
    assert {s.key[1] for s in analysis.series} == {"upper_arm", "forearm", "shoulder", "elbow"}
    page = render_html(analysis, {})
    assert "No anthropometric reference band" in page and "no finite estimate" in page


def test_cli_writes_html_png_and_csv(report_store: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out, pngs, table = tmp_path / "report.html", tmp_path / "png", tmp_path / "report.csv"
    argv = ["report", SUBJECT, "--out", str(out), "--png", str(pngs), "--csv", str(table), "--store", report_store]
    assert main(argv) == 0
    assert "1 change(s) beyond the uncertainty flagged" in capsys.readouterr().out
    page = out.read_text()
    assert SUBJECT in page and OTHER not in page and "other_subject" not in page
    assert "Elbow friction (passive moment) rose from" in page and "NOT VALID" in page
    assert all(f"rec_{i:03d}.mcap" in page for i in range(6))
    assert len(re.findall(r"src='data:image/png;base64,", page)) == 18
    assert not re.search(r"(src|href)=['\"]?(https?:|//|file:)", page) and "<script" not in page
    assert len(list(pngs.glob("*.png"))) == 18
    rows = list(csv.DictReader(table.open()))
    assert len(rows) == 6 * 18
    flagged = [r for r in rows if r["change_from_previous_flagged"] == "1"]
    assert [(r["parameter"], r["session_time_utc"]) for r in flagged] == [
        ("Elbow friction (passive moment)", "2024-06-29T07:00:00Z")
    ]


def test_cli_errors(report_store: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["report", "NOBODY", "--out", str(tmp_path / "r.html"), "--store", report_store]) == 5
    assert "unknown subject NOBODY" in capsys.readouterr().err
    assert main(["report", SUBJECT, "--store", report_store]) == 2
    assert "nothing to write" in capsys.readouterr().err
    assert not (tmp_path / "r.html").exists()
