"""The report's precision of the latest session: each static and passive moment's SD, its largest uncertainty term
in plain words and what would shrink it, from the budget the store kept; nothing where the store has none.

Simulated sessions of one arm (bsp_ros.clinic.histories, 0.2 N of sensor offset per axis, markers re-placed by up to
3 mm): untared, the assumed sensor zero (1 N per axis) dominates the upper arm's and forearm's static moments and the
hand's short lever leaves its static moment to the marker placement; tared, the zero's share shrinks to the tare's
own and the marker placement leads everywhere.
"""

from __future__ import annotations

import copy
import datetime
import re
import shutil
import subprocess
from html import unescape
from pathlib import Path
from typing import Any

import pytest

from bsp_ros.cli import main
from bsp_ros.clinic.histories import Patient, session_estimate
from bsp_ros.clinic.report import analyse
from bsp_ros.clinic.report.detail import PASSIVE
from bsp_ros.clinic.report.labels import plain_name
from bsp_ros.clinic.report.precision import BUDGET_TITLE, PRECISION_TITLE, precision_rows
from bsp_ros.clinic.report.term_words import TERM_REMEDIES, TERM_WORDS, term_words
from bsp_ros.clinic.store import SubjectRecord, open_store
from bsp_ros.core.identification.ledger import Term

PATIENT = Patient()
UNTARED, TARED, OLDER = "P301", "P302", "P303"
STATIC = {s: ("segments", s, "static_moment_kgm") for s in ("upper_arm", "forearm", "hand")}
ZERO_WORDS = TERM_WORDS[Term.SENSOR_ZERO]
TARE_REMEDY = TERM_REMEDIES[Term.SENSOR_ZERO]
POPPLER = shutil.which("pdftotext") is not None


def _without_budget(document: dict[str, Any]) -> dict[str, Any]:
    """``document`` as the estimator wrote it before quantities carried a budget."""
    old = copy.deepcopy(document)
    for group in ("segments", "joints"):
        for quantities in old[group].values():
            for q in quantities.values():
                if isinstance(q, dict):
                    q.pop("budget", None)
    return old


@pytest.fixture(scope="module")
def documents() -> dict[str, dict[str, Any]]:
    """The latest session of each subject as identified (its budget is the truth the report must render)."""
    return {
        UNTARED: session_estimate(PATIENT, 7, 7),
        TARED: session_estimate(PATIENT, 7, 8, tared=True),
        OLDER: _without_budget(session_estimate(PATIENT, 7, 9)),
    }


@pytest.fixture(scope="module")
def store(documents: dict[str, dict[str, Any]], tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Each subject: an older session without a budget (day 0), then its latest session (day 7)."""
    path = tmp_path_factory.mktemp("precision") / "clinic.sqlite"
    for k, (subject, latest) in enumerate(documents.items()):
        _fill(path, subject, 100 + k, latest)
    return path


def _fill(path: Path, subject: str, older_seed: int, latest: dict[str, Any]) -> None:
    with open_store(path) as opened:
        opened.set_subject(SubjectRecord(subject, PATIENT.body_mass_kg, PATIENT.height_m, PATIENT.sex, "left"))
        opened.add_estimate(_without_budget(session_estimate(PATIENT, 0, older_seed)), subject)
        opened.add_estimate(latest, subject)


@pytest.fixture(scope="module")
def reports(store: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, tuple[str, str]]:
    """``subject -> (HTML text, PDF text)`` of ``bsp report``."""
    out = tmp_path_factory.mktemp("reports")
    written = {}
    for subject in (UNTARED, TARED, OLDER):
        html, pdf = out / f"{subject}.html", out / f"{subject}.pdf"
        assert main(["report", subject, "--out", str(html), "--pdf", str(pdf), "--store", str(store)]) == 0
        text = _pdf_text(pdf) if POPPLER else ""
        written[subject] = (html.read_text(encoding="utf-8"), text)
    return written


def _pdf_text(pdf: Path, first: int = 1, last: int = 99) -> str:
    command = ["pdftotext", "-f", str(first), "-l", str(last), str(pdf), "-"]
    return " ".join(subprocess.run(command, capture_output=True, text=True, check=True).stdout.split())


def _table(html: str, table_id: str) -> dict[str, list[str]]:
    """``parameter -> cells`` of an HTML table of the report."""
    found = re.search(rf"<table id='{table_id}'>(.*?)</table>", html, re.S)
    assert found is not None, table_id
    rows = {}
    for row in re.findall(r"<tr>(.*?)</tr>", found.group(1), re.S)[1:]:
        cells = [" ".join(unescape(re.sub(r"<[^>]+>", "", c)).split()) for c in re.findall(r"<td[^>]*>(.*?)</td>", row)]
        rows[cells[0]] = cells
    return rows


def _name(key: tuple[str, str, str]) -> str:
    name = plain_name(key)
    return name[0].upper() + name[1:]


def _share(document: dict[str, Any], key: tuple[str, str, str], term: Term) -> float:
    q = document[key[0]][key[1]][key[2]]
    return float(q["budget"][str(term)] ** 2 / q["std"] ** 2)


def test_every_term_has_plain_words_and_a_remedy() -> None:
    assert set(TERM_WORDS) == set(TERM_REMEDIES) == set(Term)
    assert all(TERM_WORDS[t] and TERM_REMEDIES[t] for t in Term)
    assert term_words("sensor_zero", tared=True) != ZERO_WORDS  # what is left with a tare is the tare's own
    assert term_words("a_future_term", tared=False) == "a future term"


def test_untared_static_moments_name_the_sensor_zero_and_the_tare(
    documents: dict[str, dict[str, Any]], reports: dict[str, tuple[str, str]]
) -> None:
    html, _ = reports[UNTARED]
    rows = _table(html, "precision")
    document = documents[UNTARED]
    for segment in ("upper_arm", "forearm"):
        key = STATIC[segment]
        share = _share(document, key, Term.SENSOR_ZERO)
        assert share > 0.5  # the physics: a 1 N zero on the whole arm's lever
        _, arm, session, latest, words, remedy = rows[_name(key)]
        assert (arm, session) == ("Left", "2, 2024-06-08")  # the latest session, not the older one
        assert words == f"{ZERO_WORDS}, {100 * share:.0f} %", words
        assert remedy.lower() == TARE_REMEDY.lower()
        q = document["segments"][segment]["static_moment_kgm"]
        assert latest.endswith(f"± {q['std']:.2g} kg·m (± {100 * q['std'] / q['value']:.0f} %)"), latest
    # The hand's 8 cm lever: its static moment is set by where the contact point and markers sit.
    hand = rows[_name(STATIC["hand"])]
    assert hand[4].startswith(TERM_WORDS[Term.MARKER_PLACEMENT]) and _share(
        document, STATIC["hand"], Term.MARKER_PLACEMENT
    ) > _share(document, STATIC["hand"], Term.SENSOR_ZERO)
    # Every passive parameter the session decided is there, with its largest term.
    passive = [
        ("joints", joint, quantity)
        for joint, quantities in document["joints"].items()
        for quantity, q in quantities.items()
        if quantity in PASSIVE and isinstance(q, dict) and q.get("budget")
    ]
    assert len(passive) == 3 and all(_name(key) in rows for key in passive)
    friction = _name(("joints", "elbow", "coulomb_nm"))
    assert rows[friction][4].startswith(TERM_WORDS[Term.MARKER_PLACEMENT])
    # The engineer's appendix holds every term, in the estimator's own names and remedy.
    budget = _table(html, "budget")[_name(STATIC["upper_arm"])]
    assert budget[4].startswith("sensor_zero ") and "marker_placement" in budget[4]
    assert budget[5] == Term.SENSOR_ZERO.remedy


def test_a_tared_session_names_what_is_left(
    documents: dict[str, dict[str, Any]], reports: dict[str, tuple[str, str]]
) -> None:
    rows = _table(reports[TARED][0], "precision")
    for segment in ("upper_arm", "forearm"):
        key = STATIC[segment]
        assert _share(documents[TARED], key, Term.SENSOR_ZERO) < 0.01
        words, remedy = rows[_name(key)][4:6]
        assert words.startswith(TERM_WORDS[Term.MARKER_PLACEMENT]) and ZERO_WORDS not in words
        assert "tare" not in remedy


def test_no_budget_in_the_store_says_nothing(store: Path, reports: dict[str, tuple[str, str]]) -> None:
    html, text = reports[OLDER]
    assert PRECISION_TITLE not in html and BUDGET_TITLE not in html and "id='precision'" not in html
    assert PRECISION_TITLE not in text
    with open_store(store) as opened:
        analysis = analyse(OLDER, opened.sessions(OLDER))
    assert precision_rows(analysis, clinician=False) == []


@pytest.mark.skipif(not POPPLER, reason="needs poppler-utils (pdftotext; .ci/services.sh)")
def test_the_pdf_names_the_sensor_zero_and_the_tare_below_an_unchanged_page_one(
    store: Path, documents: dict[str, dict[str, Any]], reports: dict[str, tuple[str, str]], tmp_path: Path
) -> None:
    html, text = reports[UNTARED]
    assert PRECISION_TITLE in text and BUDGET_TITLE in text
    detail = text.split(PRECISION_TITLE, 1)[1]
    upper_arm = detail.split(_name(STATIC["upper_arm"]), 1)[1].split(_name(STATIC["forearm"]), 1)[0]
    assert f"Largest source: {ZERO_WORDS}" in upper_arm and f"More precise with: {TARE_REMEDY}" in upper_arm
    first = html.split("<section id='first-page'>")[1].split("</section>")[0]
    assert PRECISION_TITLE not in first
    # Page 1 is the same text whether the store kept the budget or not.
    bare = tmp_path / "bare.sqlite"
    _fill(bare, UNTARED, 100, _without_budget(documents[UNTARED]))
    pages = []
    for path in (store, bare):
        pdf = tmp_path / f"{path.stem}.pdf"
        assert main(["report", UNTARED, "--pdf", str(pdf), "--store", str(path)]) == 0
        pages.append(re.sub(r"made \S+ \S+ UTC|Page 1 of \d+", "", _pdf_text(pdf, 1, 1)))  # stamp, count
        assert _pdf_text(pdf, 2, 2).startswith("Detail: every parameter")
    assert pages[0] == pages[1] and PRECISION_TITLE not in pages[0]


def test_an_untared_latest_session_s_arm_weight_is_labelled_left_out(tmp_path: Path) -> None:
    """T1 (report_histories): a 0.3 kg handle, the latest visit untared. Its passive moments are used and shown as
    they are; its static moments, which carry the handle's weight, say that the report leaves them out."""
    from report_histories import UNTARED as T1
    from report_histories import VISITS, build_untared

    from bsp_ros.clinic.report.html import render_html
    from bsp_ros.clinic.report.precision import UNTARED_LEFT_OUT

    store = build_untared(tmp_path / "clinic.sqlite")
    with open_store(store) as opened:
        analysis = analyse(T1, opened.sessions(T1), pool=opened.sessions(), subject_record=opened.subject_record(T1))
    rows = precision_rows(analysis, clinician=True)
    assert rows and {row.session for row in rows} == {str(VISITS)} and not any(row.tared for row in rows)
    for row in rows:
        weight = row.key[2] == "static_moment_kgm"
        assert bool(row.left_out) == weight, row.key
        assert row.latest.endswith(f"; not used: {UNTARED_LEFT_OUT}") == weight, row.latest
    html = render_html(analysis, None, [], datetime.datetime(2026, 1, 1, tzinfo=datetime.UTC))
    precision = html.split(f"{PRECISION_TITLE}</h3>")[1].split("</table>")[0]
    assert precision.count("not used: recorded without a tare") == len(STATIC)
