"""Done-when of issue 12: three simulated sessions, one change beyond the MDC and one within it.

The report's summary names exactly the planted change, and in headless Chromium the summary comes first.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from test_report_browser import CHROMIUM, _chromium  # same directory: pytest puts it on sys.path

from bsp_ros.bag.writer import write_session_bag
from bsp_ros.cli import main
from bsp_ros.clinic.mdc import mdc95_from_sem
from bsp_ros.clinic.store import open_store
from bsp_ros.core.simulation import PassiveTruth, human_arm_cell, simulate_cell

SUBJECT = "P042"
WEEK_NS = 7 * 86_400 * 10**9
START_NS = 1_717_225_200 * 10**9  # 2024-06-01T07:00:00Z
BASE_COULOMB_NM = (0.5, 0.28, 0.06)
ELBOW_JUMP_NM = 0.07  # session 3: elbow friction 0.28 -> 0.35 N m, far beyond its MDC95 (~0.002 N m)
WITHIN_FRACTION = 0.3  # session 2: the shoulder friction moves by 0.3 x its MDC95, and stays there


def _add_session(tmp_path: Path, store: Path, index: int, coulomb_nm: tuple[float, ...]) -> None:
    spec = human_arm_cell(
        passive=PassiveTruth(coulomb_nm=coulomb_nm), duration_s=120.0, start_ns=START_NS + index * WEEK_NS, seed=index
    )
    bag = write_session_bag(tmp_path / f"rec_{index}", simulate_cell(spec).session, seed=index)
    assert main(["sessions", "add", str(bag), "--subject", SUBJECT, "--store", str(store)]) == 0


@pytest.fixture(scope="module")
def planted(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, float]:
    """The store with the three sessions, and the shoulder change planted within the MDC."""
    tmp_path = tmp_path_factory.mktemp("planted")
    store = tmp_path / "sessions.sqlite"
    _add_session(tmp_path, store, 0, BASE_COULOMB_NM)
    with open_store(store) as opened:
        (first,) = opened.sessions(SUBJECT)
    sem = first.repeatability["parameters"]["joints.shoulder.coulomb_nm"]["sem"]
    within_nm = WITHIN_FRACTION * mdc95_from_sem(sem)
    shoulder = BASE_COULOMB_NM[0] + within_nm
    _add_session(tmp_path, store, 1, (shoulder, *BASE_COULOMB_NM[1:]))
    _add_session(tmp_path, store, 2, (shoulder, BASE_COULOMB_NM[1] + ELBOW_JUMP_NM, BASE_COULOMB_NM[2]))
    return store, within_nm


@pytest.mark.slow
def test_summary_names_exactly_the_planted_change(planted: tuple[Path, float], tmp_path: Path) -> None:
    store, within_nm = planted
    with open_store(store) as opened:
        sessions = opened.sessions(SUBJECT)
    assert len(sessions) == 3 and all(r.quality.valid and r.repeatability["n_valid_cycles"] >= 3 for r in sessions)
    page = tmp_path / "report.html"
    assert main(["report", SUBJECT, "--out", str(page), "--store", str(store)]) == 0
    html = page.read_text()
    flags = re.findall(r"<li class='flag' data-param='([^']+)' data-since='(\w+)'>", html)
    assert flags == [("joints.elbow.coulomb_nm", "previous"), ("joints.elbow.coulomb_nm", "first")]
    summary = html.split("<section id='summary'>")[1].split("</section>")[0]
    assert "The latest session changed beyond the MDC95 in: Elbow friction (passive moment)." in summary
    shoulder = summary.split("<h3>Shoulder</h3>")[1].split("<h3>")[0]
    assert "within the minimal detectable change" in shoulder and "beyond" not in shoulder
    assert within_nm > 0


@pytest.mark.slow
@pytest.mark.skipif(CHROMIUM is None, reason="needs chromium (apt-get install chromium; .ci/services.sh)")
def test_browser_shows_the_summary_first(planted: tuple[Path, float], tmp_path: Path) -> None:
    store, _ = planted
    page = tmp_path / "report.html"
    assert main(["report", SUBJECT, "--out", str(page), "--store", str(store)]) == 0
    shot = tmp_path / "shot.png"
    result = _chromium(tmp_path, f"--screenshot={shot}", "--window-size=1100,900", page.as_uri())
    assert shot.exists(), f"chromium wrote no screenshot: {result.stderr[-2000:]}"
    dom = _chromium(tmp_path, "--dump-dom", page.as_uri()).stdout
    body = dom.split("<body>")[1]
    text = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", body)).strip()
    # Right under the title: the summary, with the planted change, before any plot, table or detail.
    assert text.startswith(f"Arm parameters of subject {SUBJECT} Summary 3 session(s) from 2024-06-01 to 2024-06-15.")
    assert text.index("Elbow friction (passive moment) rose from") < text.index("Arm weight")
    first_img, first_table = body.index("<img"), body.index("<table")
    assert body.index('id="summary"') < body.index('id="arm-weight"') < min(first_img, first_table)
