"""What a report says, in plain words: who, when, what changed beyond measurement error, which sessions need care."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.clinic.report.analysis import Analysis, Change, Series
from bsp_ros.clinic.report.labels import PART_NAMES, plain_name, plain_number, with_unit
from bsp_ros.clinic.store.records import SessionRecord, format_time, ns_to_datetime
from bsp_ros.core.weight_support import support_wrench
from bsp_ros.errors import InputError

SEGMENT_ORDER = ("upper_arm", "forearm", "hand")
SUPPORT_FRACTIONS = (0.3, 0.5, 1.0)
REFERENCE_POSE_DEG = (-45.0, 90.0, 0.0)
"""Pose of the support table: upper arm 45° below horizontal forward, elbow at a right angle, wrist straight."""


def day(time_ns: int) -> str:
    """``2024-06-01`` of a session time."""
    return format_time(time_ns)[:10]


def long_day(time_ns: int) -> str:
    """``1 June 2024``."""
    moment = ns_to_datetime(time_ns)
    return f"{moment.day} {moment.strftime('%B %Y')}"


def percent(value: float | None) -> str:
    """``21 %`` (absolute, rounded; ``<1 %`` below one)."""
    if value is None:
        return "–"
    return "<1 %" if abs(value) < 1 else f"{abs(value):.0f} %"


def arm_title(analysis: Analysis, arm: str | None) -> str:
    """``Left arm (affected)``, ``Arm`` when the side is not recorded."""
    if arm is None:
        return "Arm (side not recorded)"
    status = analysis.record.arm_status(arm) if analysis.record is not None else None
    return f"{arm.capitalize()} arm" + (f" ({status})" if status else "")


def subject_line(analysis: Analysis) -> str:
    """``female, 68 kg, 1.65 m``, or a note that no body data are recorded."""
    record = analysis.record
    facts = []
    if record is not None:
        if record.sex:
            facts.append(record.sex)
        if record.body_mass_kg:
            facts.append(f"{record.body_mass_kg:.0f} kg")
        if record.height_m:
            facts.append(f"{record.height_m:.2f} m")
    return ", ".join(facts) if facts else "body data not recorded"


def period_line(analysis: Analysis) -> str:
    """``10 sessions, 1 June 2024 to 3 August 2024 (1 not usable; 5 retests)``."""
    sessions = analysis.sessions
    visits = [r for r in sessions if not r.retest]
    retests = len(sessions) - len(visits)
    bad = sum(not r.quality.valid for r in visits)
    extra = [f"{bad} not usable" for _ in range(1) if bad] + [f"{retests} retest{'s' if retests != 1 else ''}"] * (
        retests > 0
    )
    span = (
        long_day(sessions[0].session_time_ns)
        if len(sessions) == 1
        else f"{long_day(sessions[0].session_time_ns)} to {long_day(sessions[-1].session_time_ns)}"
    )
    n = len(visits)
    return f"{n} session{'s' if n != 1 else ''}, {span}" + (f" ({'; '.join(extra)})" if extra else "")


def _direction(change: Change) -> str:
    return "rose" if change.delta > 0 else "fell"


def _span(change: Change, unit: str) -> str:
    return f"{plain_number(change.before.value)} to {with_unit(change.after.value, unit)}"


def change_sentence(series: Series, changes: list[Change]) -> str:
    """One sentence on a parameter's changes beyond the MDC95 (since previous and/or since first)."""
    name = plain_name(series.key)
    parts = []
    for change in changes:
        since = "since the previous session" if change is series.since_previous else "since the first session"
        parts.append(f"{_direction(change)} {percent(change.percent)} {since} ({_span(change, series.unit)})")
    mdc = changes[0]
    explained = f"{with_unit(mdc.mdc95, series.unit)} ({percent(mdc.mdc_percent)})"
    return f"{name[0].upper()}{name[1:]} {' and '.join(parts)}, beyond the {explained} that measurement error explains."


def headline(analysis: Analysis, arm: str | None) -> list[str]:
    """The headline sentences of one arm: what changed beyond the MDC95, or why nothing can be said."""
    visits = [r for r in analysis.visits(arm) if r.quality.valid]
    if not visits:
        return ["No session of this arm could be evaluated yet."]
    if len(visits) == 1:
        return [f"One usable session ({long_day(visits[0].session_time_ns)}): the first measurement to compare with."]
    if not analysis.judgeable:
        return [cannot_judge(analysis)]
    sentences = [change_sentence(s, s.flagged_latest) for s in analysis.arm_series(arm) if s.flagged_latest]
    if not sentences:
        first, last = visits[0], visits[-1]
        since = (
            "the previous session"
            if len(visits) == 2
            else f"the previous session or the first ({long_day(first.session_time_ns)})"
        )
        when = long_day(last.session_time_ns)
        sentences.append(f"No change beyond measurement error in the latest session ({when}) since {since}.")
    latest = analysis.visits(arm)[-1]
    if not latest.quality.valid:
        sentences.insert(
            0,
            f"The latest session ({long_day(latest.session_time_ns)}) could not be evaluated; the session before "
            "it is compared instead.",
        )
    return sentences


def cannot_judge(analysis: Analysis) -> str:
    """Why changes cannot be judged yet, and how to record a retest."""
    have = max(analysis.own_pairs, analysis.cell_pairs)
    recorded = "no retest has" if have == 0 else f"only {have} retest{'s have' if have != 1 else ' has'}"
    return (
        f"Changes cannot be judged against measurement error yet: {recorded} been recorded, "
        f"{analysis.min_pairs} are needed. To record a retest, measure the patient a second time "
        "on the same day after taking the arm out of the robot and re-attaching it (markers re-placed), and add "
        "it as a retest (bsp sessions add … --retest)."
    )


def error_source(analysis: Analysis) -> str:
    """Where the measurement error comes from, in one sentence."""
    judged = [s for s in analysis.series if s.judged and s.error.known]
    if not judged:
        return "No measurement error is known yet (no or too few retests): changes are not judged."
    error = judged[0].error
    whose = "this patient" if error.source == "subject" else f"{error.n_subjects} patient(s) measured in this cell"
    # The agreement differs per quantity: name the one it belongs to, or give the range over those judged.
    iccs = [(s.error.icc, s.label) for s in judged if s.error.icc is not None]
    if len(iccs) == 1:
        icc = f"; agreement (ICC) {iccs[0][0]:.2f} for {iccs[0][1].lower()}"
    elif iccs:
        low, high = min(i for i, _ in iccs), max(i for i, _ in iccs)
        icc = f"; agreement (ICC) {low:.2f} to {high:.2f} over the {len(iccs)} quantities judged"
    else:
        icc = ""
    return (
        f"Measurement error (MDC95) from {error.n_pairs} same-day retests of {whose}{icc}. A change is reported "
        "only when it is larger."
    )


def invalid_cause(record: SessionRecord) -> tuple[str, str]:
    """Why a session could not be evaluated and what to do, in plain words: the cause and action of the estimator's
    first finding that made it invalid (a session stored without findings gives a general line)."""
    verdict = record.quality.verdict()
    if verdict is None or not verdict.spec.cause:
        return "the measurement could not be evaluated", "repeat the session"
    where = PART_NAMES.get(verdict.where, verdict.where).lower()
    return verdict.spec.cause.format(where=where), verdict.spec.action or "repeat the session"


@dataclass(frozen=True)
class SessionRow:
    """One line of the session list (``retest``: a same-day retest, kept for the measurement error)."""

    number: int
    date: str
    arm: str
    status: str
    attention: bool
    retest: bool = False


def session_rows(analysis: Analysis) -> list[SessionRow]:
    """The session list: only invalid sessions and changes beyond measurement error need attention."""
    flagged: dict[int | None, list[str]] = {}
    for series in analysis.series:
        for change in series.changes:
            sign = "+" if change.delta > 0 else "−"
            flagged.setdefault(change.after.session_id, []).append(
                f"{plain_name(series.key)} {sign}{percent(change.percent)}"
            )
    rows = []
    for record in analysis.sessions:
        arm = (record.arm or "–").capitalize()
        if not record.quality.valid:
            cause, action = invalid_cause(record)
            rows.append(
                SessionRow(
                    record.number or 0, day(record.session_time_ns), arm, f"Not usable: {cause}; {action}.", True
                )
            )
        elif record.retest:
            rows.append(
                SessionRow(
                    record.number or 0, day(record.session_time_ns), arm, "Retest (for measurement error)", False, True
                )
            )
        elif record.id in flagged:
            text = "Change beyond measurement error: " + "; ".join(flagged[record.id])
            rows.append(SessionRow(record.number or 0, day(record.session_time_ns), arm, text, True))
        else:
            rows.append(SessionRow(record.number or 0, day(record.session_time_ns), arm, "Usable", False))
    return rows


def first_page_rows(rows: list[SessionRow], limit: int | None) -> tuple[list[SessionRow], str]:
    """The rows the first page lists, and a note on those left out (empty when all are listed).

    A long history keeps its latest sessions and its baseline, the first usable session that changes "since the
    first session" are measured from: a list without it leaves a therapist no way to see where progress started.
    """
    if limit is None or len(rows) <= limit:
        return rows, ""
    baseline = next((r for r in rows if not r.attention and not r.retest), rows[0])
    latest = rows[-(limit - 1) :]
    if baseline in latest:
        latest = rows[-limit:]
        return latest, f"The latest {len(latest)} of {len(rows)} sessions; all are listed in the detail."
    return (
        [baseline, *latest],
        f"The baseline (session {baseline.number}) and the latest {len(latest)} of {len(rows)} sessions; all are "
        "listed in the detail.",
    )


def quality_notes(record: SessionRecord) -> list[str]:
    """Plain notes on a session's quality for the detail pages (not red: they need no action)."""
    notes = []
    if not record.quality.tare_applied:
        notes.append("no tare (sensor zero) recording applied")
    if record.quality.warnings:
        notes.append(f"{len(record.quality.warnings)} technical note(s) from the estimator")
    return notes


@dataclass(frozen=True)
class SupportRow:
    """The support wrench at the reference pose for one support fraction."""

    fraction: float
    wrench_yzx: tuple[float, float, float]
    std_yzx: tuple[float, float, float]


def support_table(analysis: Analysis, arm: str | None) -> tuple[list[SupportRow], str]:
    """Support forces implied by the arm's latest usable static moments at :data:`REFERENCE_POSE_DEG`."""
    latest = next((r for r in reversed(analysis.visits(arm)) if r.quality.valid), None)
    if latest is None:
        return [], "No usable session: no support settings can be derived."
    segments = [s for s in SEGMENT_ORDER if ("segments", s, "static_moment_kgm") in latest.parameters]
    beta = [latest.parameters[("segments", s, "static_moment_kgm")] for s in segments]
    lengths = [latest.parameters.get(("segments", s, "length_m")) for s in segments]
    if len(segments) < 2 or any(q.value is None for q in beta) or any(q is None or q.value is None for q in lengths):
        return [], f"Session {latest.number} lacks static moments or segment lengths: no support settings derived."
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
            std = np.sqrt(np.clip(np.diag(wrench.covariance), 0.0, None))
            rows.append(
                SupportRow(
                    fraction,
                    (float(wrench.wrench_yzx[0]), float(wrench.wrench_yzx[1]), float(wrench.wrench_yzx[2])),
                    (float(std[0]), float(std[1]), float(std[2])),
                )
            )
    except InputError as error:
        return [], f"No support settings derived: {error}"
    note = (
        f"From session {latest.number} ({long_day(latest.session_time_ns)}), with the upper arm 45° below "
        "horizontal, the elbow at a right angle and the wrist straight: the force the robot applies at the handle "
        "(forward, upward) and the moment about the handle axis, so that it carries the given share of the "
        "arm's weight. Live, the robot computes it at the current pose."
    )
    return rows, note
