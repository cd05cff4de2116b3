"""The first page's session list keeps the baseline a long history's progress is measured from, and every session
that needs attention."""

from __future__ import annotations

from bsp_ros.clinic.report.summary import SessionRow, first_page_rows


def _rows(n: int) -> list[SessionRow]:
    rows = [SessionRow(1, "day 1", "Right", "Not usable: the elbow did not move; repeat.", True)]
    rows.append(SessionRow(2, "day 1", "Right", "Retest (for measurement error)", False, retest=True))
    rows += [SessionRow(k, f"day {k}", "Right", "Usable", False) for k in range(3, n + 1)]
    return rows


def test_a_long_history_lists_its_baseline_and_its_latest_sessions() -> None:
    rows = _rows(20)
    shown, note = first_page_rows(rows, 12)
    # Session 1 was not usable (kept: it needs attention) and session 2 a retest: the baseline is session 3.
    assert [r.number for r in shown] == [1, 3, *range(11, 21)]
    assert note == (
        "The baseline (session 3), every session that needs attention and the latest: 12 of 20 sessions; all are "
        "listed in the detail."
    )


def test_a_flagged_session_is_never_left_out() -> None:
    rows = _rows(20)
    rows[6] = SessionRow(7, "day 7", "Right", "Change beyond measurement error: elbow friction −22 %", True)
    shown, _ = first_page_rows(rows, 12)
    assert [r.number for r in shown] == [1, 3, 7, *range(12, 21)]


def test_a_short_history_is_listed_whole() -> None:
    rows = _rows(12)
    assert first_page_rows(rows, 12) == (rows, "")
    assert first_page_rows(rows, None) == (rows, "")


def test_a_baseline_among_the_latest_sessions_takes_no_extra_row() -> None:
    rows = _rows(13)
    shown, note = first_page_rows(rows, 12)
    assert [r.number for r in shown] == [1, *range(3, 14)]  # the retest (2) makes room for the invalid session
    assert "12 of 13 sessions" in note
