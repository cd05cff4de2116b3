"""The plain-language summary a report opens with: per joint, per segment, and the support the weights imply."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bsp_ros.clinic.report.analysis import Analysis, Change, Series
from bsp_ros.clinic.report.labels import PART_NAMES, QUANTITIES
from bsp_ros.clinic.store.records import SessionRecord, format_time
from bsp_ros.core.weight_support import support_wrench
from bsp_ros.errors import InputError

JOINT_ORDER = ("shoulder", "elbow", "wrist")
SEGMENT_ORDER = ("upper_arm", "forearm", "hand")
SUPPORT_FRACTIONS = (0.3, 0.5, 1.0)
REFERENCE_POSE_DEG = (-45.0, 90.0, 0.0)
"""Pose of the support table: upper arm 45 deg below horizontal forward, elbow at a right angle, wrist straight."""


def day(time_ns: int) -> str:
    """``2024-06-01`` of a session time."""
    return format_time(time_ns)[:10]


def number(value: float | None, unit: str = "") -> str:
    """``0.28 N·m``; ``–`` for a missing value."""
    if value is None:
        return "–"
    return f"{value:.3g} {unit}".strip()


def _signed(value: float, unit: str) -> str:
    return f"{'+' if value >= 0 else '−'}{abs(value):.2g} {unit}".strip()


def change_clause(change: Change | None, since: str, unit: str) -> str:
    """``since the previous session: +0.12 N·m, beyond the MDC95 of 0.0015 N·m`` (or within, or not judged)."""
    if change is None:
        return f"no comparison since the {since} session (too few valid sessions)"
    text = f"since the {since} session ({day(change.before.time_ns)}): {_signed(change.delta, unit)}"
    if change.mdc95 is None:
        return text + ", which cannot be judged (no repeatability measured for these sessions)"
    if change.beyond_mdc:
        return text + f", beyond the minimal detectable change (MDC95 {number(change.mdc95, unit)}): a real change"
    return text + f", within the minimal detectable change (MDC95 {number(change.mdc95, unit)}): no detectable change"


def _quantity_name(series: Series) -> str:
    quantity = series.key[2]
    return QUANTITIES[quantity][0].split(" (")[0] if quantity in QUANTITIES else quantity.replace("_", " ")


def series_sentence(series: Series, what: str) -> str:
    """One sentence on one parameter: first and latest value, trend, and the two MDC comparisons."""
    valid = [p for p in series.points if p.valid and p.value is not None]
    if not valid:
        return f"{what}: no valid estimate in any session."
    first, latest = valid[0], valid[-1]
    trend = ""
    if series.since_first is not None and series.since_first.mdc95 is not None:
        trend = (
            (" rising" if series.since_first.delta > 0 else " falling") if series.since_first.beyond_mdc else " steady"
        )
        trend = f",{trend} over {len(valid)} valid sessions"
    head = (
        f"{what} {number(latest.value, series.unit)} in the latest valid session ({day(latest.time_ns)})"
        if len(valid) == 1
        else f"{what} {number(first.value, series.unit)} in the first valid session, "
        f"{number(latest.value, series.unit)} in the latest ({day(latest.time_ns)}){trend}"
    )
    clauses = [change_clause(series.since_previous, "previous", series.unit)]
    if series.since_first is not None:
        clauses.append(change_clause(series.since_first, "first", series.unit))
    elif len(valid) == 2:
        clauses[0] = clauses[0].replace("previous session", "previous (first) session")
    if len(valid) < 2:
        return head + "."
    return f"{head}. Change {'; '.join(clauses)}."


@dataclass(frozen=True)
class PartSummary:
    """The summary of one joint (passive moments) or segment (static moment)."""

    part: str
    title: str
    sentences: tuple[str, ...]
    flagged: tuple[Change, ...]


def joint_summaries(analysis: Analysis) -> list[PartSummary]:
    """Per joint: every passive-moment parameter's trend and whether the latest session changed beyond the MDC."""
    found = []
    joints = sorted({s.key[1] for s in analysis.series if s.key[0] == "joints"}, key=_order(JOINT_ORDER))
    for joint in joints:
        series = [s for s in analysis.series if s.key[:2] == ("joints", joint)]
        sentences = tuple(series_sentence(s, f"Passive {_quantity_name(s)}") for s in series)
        flagged = tuple(c for s in series for c in (s.since_previous, s.since_first) if c is not None and c.beyond_mdc)
        found.append(PartSummary(joint, PART_NAMES.get(joint, joint), sentences, flagged))
    return found


def segment_summaries(analysis: Analysis) -> list[PartSummary]:
    """Per segment: the static moment (the arm's weight about the proximal joint) and its changes."""
    found = []
    for s in analysis.series:
        if s.key[0] == "segments" and s.key[2] == "static_moment_kgm":
            flagged = tuple(c for c in (s.since_previous, s.since_first) if c is not None and c.beyond_mdc)
            sentence = series_sentence(s, "Static moment")
            found.append(PartSummary(s.key[1], PART_NAMES.get(s.key[1], s.key[1]), (sentence,), flagged))
    return sorted(found, key=lambda p: _order(SEGMENT_ORDER)(p.part))


def session_marks(record: SessionRecord) -> list[str]:
    """What to mark a session with: ``NOT VALID``, ``no tare``, ``N warning(s)``."""
    marks = []
    if not record.quality.valid:
        marks.append("NOT VALID")
    if not record.quality.tare_applied:
        marks.append("no tare")
    if record.quality.warnings:
        marks.append(f"{len(record.quality.warnings)} warning(s)")
    return marks


def session_notes(analysis: Analysis) -> list[str]:
    """One line per marked session: ``session 3 (2024-06-15): NOT VALID, no tare``."""
    return [
        f"Session {r.id} ({day(r.session_time_ns)}): {', '.join(marks)}"
        for r in analysis.sessions
        if (marks := session_marks(r))
    ]


@dataclass(frozen=True)
class SupportRow:
    """The support wrench at the reference pose for one support fraction."""

    fraction: float
    wrench_yzx: tuple[float, float, float]
    std_yzx: tuple[float, float, float]


def support_table(analysis: Analysis) -> tuple[list[SupportRow], str]:
    """Support wrenches implied by the latest valid session's static moments at :data:`REFERENCE_POSE_DEG`.

    Returns
    -------
    rows, note
        Rows for :data:`SUPPORT_FRACTIONS` (empty with the reason in ``note`` when they cannot be computed).
    """
    latest = next((r for r in reversed(analysis.sessions) if r.quality.valid), None)
    if latest is None:
        return [], "No valid session: no support settings can be derived."
    segments = [s for s in SEGMENT_ORDER if ("segments", s, "static_moment_kgm") in latest.parameters]
    beta = [latest.parameters[("segments", s, "static_moment_kgm")] for s in segments]
    lengths = [latest.parameters.get(("segments", s, "length_m")) for s in segments]
    if len(segments) < 2 or any(q.value is None for q in beta) or any(q is None or q.value is None for q in lengths):
        return [], f"Session {latest.id} lacks static moments or segment lengths: no support settings derived."
    pose = np.radians(REFERENCE_POSE_DEG[: len(segments)])
    variances = np.diag([(q.std or 0.0) ** 2 for q in beta])
    rows = []
    try:
        for fraction in SUPPORT_FRACTIONS:
            wrench = support_wrench(
                pose,
                [q.value or 0.0 for q in lengths if q is not None],
                [q.value or 0.0 for q in beta],
                fraction,
                variances,
            )
            rows.append(
                SupportRow(
                    fraction,
                    (float(wrench.wrench_yzx[0]), float(wrench.wrench_yzx[1]), float(wrench.wrench_yzx[2])),
                    (float(wrench.std[0]), float(wrench.std[1]), float(wrench.std[2])),
                )
            )
    except InputError as error:
        return [], f"No support settings derived: {error}"
    pose_text = ", ".join(
        f"{name} {deg:g}°" for name, deg in zip(JOINT_ORDER, REFERENCE_POSE_DEG[: len(segments)], strict=False)
    )
    note = (
        f"From session {latest.id} ({day(latest.session_time_ns)}) at a reference pose ({pose_text}; angles as in "
        "docs/contract.md): the wrench the robot applies to the hand, in world axes (y forward, z up) at the "
        "handle, so that it carries the given share of the arm's weight about every joint. The uncertainty ignores the "
        "correlation of the static moments (not stored). Live, `bsp/weight_support` gives it at the current pose."
    )
    return rows, note


def _order(names: tuple[str, ...]) -> Callable[[str], tuple[int, str]]:
    def key(name: str) -> tuple[int, str]:
        return (names.index(name) if name in names else len(names), name)

    return key


def headline(analysis: Analysis) -> str:
    """One line: how many sessions, and which parameters changed beyond the MDC in the latest session."""
    changed = sorted({PART_NAMES.get(c.key[1], c.key[1]) + " " + c.key[2] for c in analysis.latest_changes})
    if not any(s.since_previous is not None and s.since_previous.mdc95 is not None for s in analysis.series):
        judged = " No change can be judged: the sessions carry no repeatability (SEM) measurement."
    elif changed:
        judged = f" The latest session changed beyond the MDC95 in: {', '.join(_plain(analysis, changed))}."
    else:
        judged = " The latest session shows no change beyond the minimal detectable change."
    last = analysis.sessions[-1]
    if not last.quality.valid:
        valid = [r for r in analysis.sessions if r.quality.valid]
        used = f"the latest valid one ({day(valid[-1].session_time_ns)})" if valid else "none (no session is valid)"
        judged = f" The latest session ({day(last.session_time_ns)}) is NOT VALID; compared instead: {used}." + judged
    return f"{len(analysis.sessions)} session(s) from {day(analysis.sessions[0].session_time_ns)} to " + (
        f"{day(last.session_time_ns)}.{judged}"
    )


def _plain(analysis: Analysis, changed: list[str]) -> list[str]:
    labels = {
        PART_NAMES.get(s.key[1], s.key[1]) + " " + s.key[2]: s.label
        for s in analysis.series
        if s.key[0] in ("joints", "segments")
    }
    return [labels.get(c, c) for c in changed]
