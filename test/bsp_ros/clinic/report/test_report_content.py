"""Report content: trends, change flags, priors, labels, exports, without a browser."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import pytest

from bsp_ros.cli import main
from bsp_ros.clinic.report import Point, analyse, compare, flag_changes, label, unit
from bsp_ros.clinic.report.html import render_html
from bsp_ros.clinic.store import open_store
from bsp_ros.clinic.store.samples import SAMPLE_START_NS, sample_estimate

SUBJECT = "P007"  # as planted by the report_store fixture (conftest.py)
OTHER = "Q9other"


def _point(time_ns: int, value: float, sem: float | None, valid: bool = True) -> Point:
    return Point(None, time_ns, value, 0.001, "data", valid, None, sem)


def test_change_is_flagged_only_beyond_the_mdc95() -> None:
    key = ("joints", "elbow", "coulomb_nm")
    sem = 0.1 / (1.96 * 2**0.5)  # MDC95 = 1.96 sqrt(2) SEM = 0.1
    just_inside = [_point(1, 1.0, sem), _point(2, 1.0999, sem)]
    just_outside = [_point(1, 1.0, sem), _point(2, 1.1001, sem)]
    assert flag_changes(key, just_inside) == []
    (change,) = flag_changes(key, just_outside)
    assert change.mdc95 == pytest.approx(0.1) and change.mdc_ratio == pytest.approx(1.001)
    invalid_between = [_point(1, 1.0, sem), _point(2, 5.0, sem, valid=False), _point(3, 0.5, sem)]
    assert [(c.before.time_ns, c.after.time_ns) for c in flag_changes(key, invalid_between)] == [(1, 3)]


def test_no_change_is_claimed_without_a_measured_sem() -> None:
    key = ("joints", "elbow", "coulomb_nm")
    (change,) = [compare(key, _point(1, 1.0, None), _point(2, 9.0, 0.01))]
    assert change.mdc95 is None and not change.beyond_mdc
    assert flag_changes(key, [_point(1, 1.0, None), _point(2, 9.0, 0.01)]) == []


def test_baseline_sessions_set_the_sem_when_larger(tmp_path: Path) -> None:
    key = ("joints", "elbow", "coulomb_nm")
    values = [0.30, 0.34, 0.30, 0.37]  # baseline 0.30, 0.34: successive-difference SEM 0.04 / sqrt(2)
    with open_store(tmp_path / "s.sqlite") as store:
        for i, value in enumerate(values):
            estimate = sample_estimate(
                i, start_time_ns=SAMPLE_START_NS + i * 10**12, overrides={key: (value, 0.001)}, sem_rel=0.001
            )
            store.add_estimate(estimate, "B1")
        records = store.sessions("B1")
    (elbow,) = [s for s in analyse("B1", records).series if s.key == key]
    assert elbow.since_previous is not None and elbow.since_previous.beyond_mdc  # cycle SEM alone: tiny
    (elbow,) = [s for s in analyse("B1", records, baseline_sessions=2).series if s.key == key]
    assert elbow.points[-1].sem == pytest.approx(0.04 / 2**0.5)
    assert elbow.since_previous is not None and not elbow.since_previous.beyond_mdc  # 0.07 < 1.96 * 0.04 = 0.0784


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
    assert "changed beyond the MDC95 in 1 comparison(s)" in capsys.readouterr().out
    page = out.read_text()
    assert SUBJECT in page and OTHER not in page and "other_subject" not in page
    assert "Elbow friction (passive moment) rose from" in page and "NOT VALID" in page and "no tare" in page
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
    assert main(["report", SUBJECT, "--pdf", str(tmp_path / "r.pdf"), "--baseline", "1", "--store", report_store]) == 2
    assert "at least 2" in capsys.readouterr().err


def test_summary_leads_and_names_the_latest_change(report_store: str, tmp_path: Path) -> None:
    out = tmp_path / "report.html"
    assert main(["report", SUBJECT, "--out", str(out), "--store", report_store]) == 0
    page = out.read_text()
    order = [page.index(f"id='{name}'") for name in ("summary", "arm-weight", "trends", "quality", "detail")]
    assert order == sorted(order) and page.index("id='summary'") < page.index("<img")
    flags = re.findall(r"<li class='flag' data-param='([^']+)' data-since='(\w+)'>", page)
    # Elbow friction jumped at session 5 and stayed: the latest (6) differs from the first, not from session 5.
    assert flags == [("joints.elbow.coulomb_nm", "first")]
    assert "Session 2 (2024-06-08): no tare" in page and "Session 3 (2024-06-15): NOT VALID, 1 warning(s)" in page
    assert "id='support'" in page and "SEM from" not in page.split("id='detail'")[0]


def test_pdf_export_has_summary_and_plots(report_store: str, tmp_path: Path) -> None:
    pdf = tmp_path / "report.pdf"
    assert main(["report", SUBJECT, "--pdf", str(pdf), "--store", report_store]) == 0
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF-")
    pages = len(re.findall(rb"/Type\s*/Page\b", data))
    assert pages >= 1 + 18  # text page(s) and one page per plotted parameter


def test_an_invalid_latest_session_is_named_and_not_compared(tmp_path: Path) -> None:
    key = ("joints", "elbow", "coulomb_nm")
    with open_store(tmp_path / "s.sqlite") as store:
        for i, valid in enumerate((True, True, False)):
            planted = {key: (2.0, 0.01)} if i == 2 else None  # a wild value in the invalid session
            estimate = sample_estimate(
                i, start_time_ns=SAMPLE_START_NS + i * 86_400 * 10**9, valid=valid, overrides=planted, sem_rel=0.05
            )
            store.add_estimate(estimate, "L1")
        analysis = analyse("L1", store.sessions("L1"))
    assert analysis.latest_changes == [] and analysis.changes == []
    page = render_html(analysis, {})
    assert "is NOT VALID; compared instead: the latest valid one (2024-06-02)" in page
