"""Simulated histories judged against retests: planted steps flagged exactly, an unchanged arm nowhere."""

from __future__ import annotations

import csv
import io
import itertools
import math

import pytest
from clinic_history import FRICTION, INVALID_VALUE_NM, STIFFNESS, UNCHANGED, History, patient

from bsp_ros.clinic.histories import HISTORY_START_NS, session_estimate
from bsp_ros.clinic.mdc import Z95, ErrorScale
from bsp_ros.clinic.report import Analysis, analyse
from bsp_ros.clinic.report.export import write_analysis_csv
from bsp_ros.clinic.report.summary import headline, headline_parts
from bsp_ros.clinic.store import open_store
from bsp_ros.errors import InputError, StoreError

ELBOW = {"coulomb": ("joints", "elbow", "coulomb_nm"), "stiffness": ("joints", "elbow", "stiffness_nm_per_rad")}


def _analysis(history: History, subject: str) -> Analysis:
    with open_store(history.store) as store:
        return analyse(
            subject, store.sessions(subject), pool=store.sessions(), subject_record=store.subject_record(subject)
        )


@pytest.mark.parametrize(
    ("subject", "which"),
    [
        (FRICTION, "coulomb"),
        (STIFFNESS, "stiffness"),
    ],
)
def test_planted_steps_are_flagged_exactly_where_beyond_the_mdc(history: History, subject: str, which: str) -> None:
    analysis = _analysis(history, subject)
    (series,) = [s for s in analysis.series if s.key == ELBOW[which]]
    plan = [visit[0 if which == "coulomb" else 1] for visit in history.plans[subject]]
    usable = [p for p in series.points if p.usable]
    assert len(usable) == len(plan), "every planned visit must be usable for this test to map steps"
    assert series.error.known and series.error.n_pairs >= 5
    planted = [b - a for a, b in itertools.pairwise(plan)]
    assert any(abs(d) > 2 * series.error.mdc95 for d in planted)  # the history plants steps well beyond the MDC
    flagged = [step.beyond_mdc for step in series.steps]
    assert flagged == [abs(d) > series.error.mdc95 for d in planted]
    # What the report flags is stricter: beyond the MDC95 widened for every comparison it makes.
    assert all(step.beyond_mdc and abs(step.delta) > step.limit for step in series.changes)
    # No other parameter of these arms is flagged anywhere.
    assert [s.key for s in analysis.series if s.changes] == [ELBOW[which]]


def test_an_unchanged_arm_is_flagged_nowhere_over_ten_sessions(history: History) -> None:
    analysis = _analysis(history, UNCHANGED)
    assert len(analysis.visits("left")) == 10 and analysis.judgeable
    assert analysis.changes == [] and analysis.latest_changes == []
    parts = headline_parts(analysis, "left")
    assert [kind for kind, _ in parts] == ["no change", "cannot be judged yet"]
    assert "elbow friction, elbow stiffness" in parts[0][1] and "wrist stiffness" in parts[1][1]
    # The day-to-day error is what the visits scatter by: the MDC is not a within-session 0.1 %. The arm's own 6
    # pairs agree with the other patient's (F-test), so the cell's 12 judge it, on the log scale (relative).
    (friction,) = [s for s in analysis.series if s.key == ELBOW["coulomb"]]
    assert (friction.error.source, friction.error.n_pairs, friction.error.scale) == ("cell", 12, ErrorScale.LOG)
    mdc95_nm = friction.error.mdc95_at(0.28)
    assert mdc95_nm is not None and mdc95_nm > 0.02 * 0.28


def test_cell_pairs_serve_a_subject_without_retests(history: History) -> None:
    analysis = _analysis(history, STIFFNESS)
    (stiffness,) = [s for s in analysis.series if s.key == ELBOW["stiffness"]]
    assert analysis.own_pairs == 0 and stiffness.error.source == "cell"
    assert stiffness.error.n_subjects == 2 and stiffness.error.icc is not None


def test_invalid_duplicate_and_future_sessions_do_not_move_the_headline(history: History) -> None:
    before = _analysis(history, FRICTION)
    sentence = headline(before, "left")
    assert sentence[0].startswith("Resistance to passive elbow movement (friction) fell 5")
    # The invalid session's absurd value is not a point of any trend or comparison.
    (friction,) = [s for s in before.series if s.key == ELBOW["coulomb"]]
    invalid = [p for p in friction.points if not p.valid]
    assert len(invalid) == 1 and invalid[0].value == INVALID_VALUE_NM
    assert all(INVALID_VALUE_NM not in (c.before.value, c.after.value) for c in friction.steps)
    with open_store(history.store) as store:
        pool = [r for r in store.sessions() if r.quality.valid]  # the cell's retest pairs judge it too
    without = analyse(
        FRICTION, [r for r in before.sessions if r.quality.valid], pool=pool, subject_record=before.record
    )
    assert headline(without, "left") == sentence
    first = session_estimate(patient(0.80, 1.5), 0, 100)  # F1 (k = 1): its first session again
    future = session_estimate(patient(0.40, 1.5), 0, 77)
    future["session"]["start_time_ns"] = HISTORY_START_NS + 7 * 365 * 86_400 * 10**9  # 2031
    with open_store(history.store) as store:
        count = len(store.sessions())
        with pytest.raises(StoreError, match="duplicate"):
            store.add_estimate(first, FRICTION)
        with pytest.raises(StoreError, match="duplicate recording"):
            store.add_estimate(first, FRICTION, session_time_ns=HISTORY_START_NS + 3_600 * 10**9)
        with pytest.raises(InputError, match="in the future"):
            store.add_estimate(future, FRICTION)
        assert len(store.sessions()) == count
    assert headline(_analysis(history, FRICTION), "left") == sentence


def test_csv_export_flags_the_planted_steps(history: History) -> None:
    analysis = _analysis(history, FRICTION)
    stream = io.StringIO()
    write_analysis_csv([analysis], stream)
    rows = [r for r in csv.DictReader(io.StringIO(stream.getvalue())) if r["quantity"] == "coulomb_nm"]
    elbow = [r for r in rows if r["part"] == "elbow"]
    assert [int(r["session_number"]) for r in elbow] == list(range(1, len(analysis.sessions) + 1))
    assert [r["session_label"] for r in elbow][:4] == ["1", "1a", "2", "2a"]  # a retest beside its session
    flagged = [r for r in elbow if r["flagged"] == "1"]
    assert len(flagged) == 2 and all(r["mdc95_source"] in ("retest pairs", "session uncertainty") for r in flagged)
    assert all(float(r["change_from_previous"]) < -float(r["flag_limit"]) for r in flagged)
    assert all(float(r["flag_limit"]) > float(r["mdc95"]) for r in flagged)  # widened for the report's comparisons
    assert {r["change_from_previous"] for r in elbow if r["retest"] == "1" or r["valid"] == "0"} == {""}


def _csv_rows(analysis: Analysis) -> dict[tuple[str, str, str, str], dict[str, str]]:
    stream = io.StringIO()
    write_analysis_csv([analysis], stream)
    rows = csv.DictReader(io.StringIO(stream.getvalue()))
    return {(r["arm"], r["part"], r["quantity"], r["session_label"]): r for r in rows if r["retest"] == "0"}


def test_csv_export_says_which_mdc95_was_used(history: History) -> None:
    analysis = _analysis(history, FRICTION)
    rows = _csv_rows(analysis)
    seen = set()
    for series in analysis.series:
        if not (series.judged and series.error.known):
            continue
        retest = series.error.mdc95
        relative = series.error.scale is ErrorScale.LOG
        for step in series.steps:
            if relative and not step.judged:
                continue  # a value at its bound 0 has no log
            row = rows[(series.arm or "", series.key[1], series.key[2], str(step.after.number))]
            a, b = step.before, step.after
            assert a.value is not None and b.value is not None
            if relative:  # relative stds, and the larger bound back in units from the earlier value
                own = Z95 * math.hypot((a.std or 0.0) / a.value, (b.std or 0.0) / b.value)
                larger = max(own, retest)
                in_unit = a.value * (math.exp(larger) - 1.0 if b.value > a.value else 1.0 - math.exp(-larger))
            else:
                own = Z95 * math.hypot(a.std or 0.0, b.std or 0.0)
                in_unit = max(own, retest)
            # The larger bound is the one used, and the column names it.
            expected = "session uncertainty" if own > retest else "retest pairs"
            assert (row["mdc95_source"], float(row["mdc95"])) == (expected, pytest.approx(in_unit))
            seen.add(expected)
    # With the cell's 12 pairs pooled, every step of this seeded history is bounded by its sessions' own uncertainty.
    assert seen == {"session uncertainty"}
    # The first session has no step: the MDC95 it shows is the retest pairs', a fall from its value.
    (friction,) = [s for s in analysis.series if s.key == ELBOW["coulomb"]]
    first = rows[("left", "elbow", "coulomb_nm", "1")]
    at_first = float(first["value"]) * (1.0 - math.exp(-friction.error.mdc95))
    assert (first["mdc95_source"], float(first["mdc95"])) == ("retest pairs", pytest.approx(at_first))
    # Without retest pairs no MDC95 is used at all, whatever the sessions' own uncertainty.
    visits = [r for r in analysis.sessions if not r.retest]
    alone = analyse(FRICTION, visits, pool=visits, subject_record=analysis.record)
    assert {(r["mdc95_source"], r["mdc95"], r["flagged"]) for r in _csv_rows(alone).values()} == {("none", "", "0")}
