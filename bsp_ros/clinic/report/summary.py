"""What a report says, in plain words: who, when, what changed beyond measurement error, which sessions need care."""

from __future__ import annotations

import statistics
from dataclasses import dataclass, replace

import numpy as np

from bsp_ros.clinic.report.analysis import RETEST_LETTERS, Analysis, Change, Series, Untared
from bsp_ros.clinic.report.labels import PART_NAMES, plain_name, plain_number, short_label, with_unit
from bsp_ros.clinic.report.speed_lines import speed_dependence_lines
from bsp_ros.clinic.store.records import ParamKey, SessionRecord, format_time, ns_to_datetime
from bsp_ros.core.findings import Severity, plain_cause
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


def short_name(key: ParamKey) -> str:
    """``elbow friction``: a parameter's short name, lower case, for lists."""
    return short_label(key).lower()


def _size(change: Change, unit: str) -> str:
    return percent(change.percent) if change.percent is not None else with_unit(abs(change.delta), unit)


def _limit_text(change: Change, unit: str) -> str:
    share = f" ({percent(change.limit_percent)})" if change.percent is not None else ""
    return f"{with_unit(change.limit, unit)}{share}"


def _step_text(change: Change, unit: str) -> str:
    sign = "+" if change.delta > 0 else "−"
    when = f"{long_day(change.before.time_ns)} to {long_day(change.after.time_ns)}"
    return f"{when} ({sign}{_size(change, unit)}, {_span(change, unit)})"


def change_sentence(series: Series, changes: list[Change] | tuple[Change, ...]) -> str:
    """One sentence on a parameter's flagged changes: since the first session, then each confirmed step with the
    limit it passed."""
    name = plain_name(series.key)
    first = series.since_first
    overall = (
        f"{_direction(first)} {_size(first, series.unit)} since the first session ({_span(first, series.unit)}), "
        if first is not None
        else ""
    )
    steps = " and from ".join(_step_text(c, series.unit) for c in changes)
    found = list(dict.fromkeys(_limit_text(c, series.unit) for c in changes))
    limits = ("limit " if len(found) == 1 else "limits ") + " and ".join(found)
    return (
        f"{name[0].upper()}{name[1:]} {overall}with a change beyond measurement error from {steps}, each "
        f"confirmed by the next session ({limits} in this report)."
    )


def possible_sentence(series: Series, change: Change) -> str:
    """Page 1's sentence on a possible change of the latest session, awaiting the next session's confirmation."""
    name = short_name(series.key)
    return (
        f"Possible change, to be confirmed by the next session: {name} {_direction(change)} "
        f"{_size(change, series.unit)} since the previous session ({_span(change, series.unit)}), beyond the "
        f"{_limit_text(change, series.unit)} that measurement error can explain in this report."
    )


CHANGE, POSSIBLE, NO_CHANGE, UNKNOWN = "change", "possible change", "no change", "cannot be judged yet"


@dataclass(frozen=True, kw_only=True)
class Verdict:
    """What the headline says of one passive parameter of one arm.

    Attributes
    ----------
    series : the parameter's series.
    status : ``change`` (a confirmed change), ``possible change`` (the latest step, awaiting the next session),
        ``no change`` or ``cannot be judged yet``.
    reason : for ``cannot be judged yet``, why and what to record.
    since : for ``no change``, what the latest session was compared with (``the previous or the first (1 June
        2024)``, ``the previous session``, or one of them only and why not the other).
    """

    series: Series
    status: str
    reason: str = ""
    since: str = ""


def _plural(count: int, word: str) -> str:
    return f"{count} {word}{'s' if count != 1 else ''}"


NOT_IN_LATEST = "not measured in the latest session. To judge it, record it with the same passive model"
AT_ZERO = "estimated at 0"


def _in_latest(series: Series, latest: SessionRecord | None) -> bool:
    """Whether ``series``' latest usable point is the latest valid visit ``latest`` (True without one)."""
    point = series.latest
    if latest is None:
        return True
    return point is not None and point.session_id == latest.id and point.time_ns == latest.session_time_ns


def _since(series: Series) -> str:
    """What a ``no change`` of ``series`` compared the latest session with, naming a comparison not judged."""
    previous, first = series.since_previous, series.since_first
    previous_judged = previous is not None and previous.judged
    first_judged = first is not None and first.judged
    if first is not None and previous_judged and first_judged:
        return f"the previous or the first ({long_day(first.before.time_ns)})"
    if first is not None and first_judged:
        return f"the first ({long_day(first.before.time_ns)}) only (the previous session's is {AT_ZERO})"
    if first is not None:
        return f"the previous session only (the first session's is {AT_ZERO})"
    return "the previous session"


def verdict(series: Series, min_pairs: int, *, latest: SessionRecord | None = None) -> Verdict:
    """Whether the latest session's change of ``series`` is judged, and what was found (see :class:`Verdict`).

    ``latest`` is the arm's latest valid visit: a parameter that session did not measure (another passive model)
    cannot be judged in it, whatever its earlier sessions show.
    """
    if not _in_latest(series, latest):
        return Verdict(series=series, status=UNKNOWN, reason=NOT_IN_LATEST)
    if series.changes:
        return Verdict(series=series, status=CHANGE)
    if series.possible is not None:
        return Verdict(series=series, status=POSSIBLE)
    usable = sum(p.usable for p in series.points)
    if usable < 2:
        return Verdict(series=series, status=UNKNOWN, reason="one usable session. The next one is compared with it")
    # A term at its bound is named as such first: its retests at 0 are no pairs on the log scale either.
    latest_changes = [c for c in (series.since_previous, series.since_first) if c is not None]
    if all(c.at_bound for c in latest_changes):
        return Verdict(
            series=series,
            status=UNKNOWN,
            reason=f"{AT_ZERO}, where the movement did not show it. To judge it, record wider or faster movements "
            "(bsp plan)",
        )
    if not series.error.known:
        return Verdict(
            series=series,
            status=UNKNOWN,
            reason=f"{_plural(series.error.n_pairs, 'retest pair')} of the {min_pairs} needed. To judge it, record "
            "a same-day retest with the same passive model (bsp sessions add … --retest)",
        )
    return Verdict(series=series, status=NO_CHANGE, since=_since(series))


def latest_visit(analysis: Analysis, arm: str | None) -> SessionRecord | None:
    """The arm's latest valid visit (retests left out), None without one."""
    return next((r for r in reversed(analysis.visits(arm)) if r.quality.valid), None)


def verdicts(analysis: Analysis, arm: str | None) -> list[Verdict]:
    """The headline's verdict on each judged passive parameter of ``arm`` that has a value (the moment at one
    angle of a passive curve only where it changed: the curve's panel shows the rest)."""
    from bsp_ros.clinic.store.curves import angle_of

    latest = latest_visit(analysis, arm)
    found = []
    for series in analysis.arm_series(arm):
        if not series.judged or not series.has_values:
            continue
        if angle_of(series.key[2]) is not None and not series.changes and series.possible is None:
            continue
        found.append(verdict(series, analysis.min_pairs, latest=latest))
    return found


def _no_change_sentences(found: list[Verdict], latest: SessionRecord) -> list[tuple[str, str]]:
    """One ``no change`` sentence per kind of comparison judged, naming its parameters."""
    groups: dict[str, list[str]] = {}
    for v in found:
        if v.status == NO_CHANGE:
            groups.setdefault(v.since, []).append(short_name(v.series.key))
    return [
        (
            NO_CHANGE,
            f"No change beyond measurement error in the latest session ({long_day(latest.session_time_ns)}) since "
            f"{since}: {', '.join(names)}.",
        )
        for since, names in groups.items()
    ]


def headline_parts(analysis: Analysis, arm: str | None) -> list[tuple[str, str]]:
    """The headline of one arm as ``(kind, sentence)``: kind ``change`` (red), ``no change``, ``cannot be judged
    yet`` or ``note``. A parameter is named under "no change" only where its change was judged in the latest
    session, with what it was compared with."""
    visits = [r for r in analysis.visits(arm) if r.quality.valid]
    if not visits:
        return [("note", "No session of this arm could be evaluated yet.")]
    if len(visits) == 1:
        return [
            (
                "note",
                f"One usable session ({long_day(visits[0].session_time_ns)}): the first measurement to compare with.",
            )
        ]
    if not analysis.judgeable:
        return [("note", cannot_judge(analysis))]
    found = verdicts(analysis, arm)
    parts = [(CHANGE, change_sentence(v.series, v.series.changes)) for v in found if v.status == CHANGE]
    parts += [
        (POSSIBLE, possible_sentence(v.series, possible)) for v in found if (possible := v.series.possible) is not None
    ]
    parts += _no_change_sentences(found, visits[-1])
    unknown: dict[str, list[str]] = {}
    for v in found:
        if v.status == UNKNOWN:
            unknown.setdefault(v.reason, []).append(short_name(v.series.key))
    for reason, names in unknown.items():
        parts.append((UNKNOWN, f"Cannot be judged yet: {', '.join(names)}. Why: {reason}."))
    latest = analysis.visits(arm)[-1]
    if not latest.quality.valid:
        parts.insert(
            0,
            (
                "note",
                f"The latest session ({long_day(latest.session_time_ns)}) could not be evaluated; the session "
                "before it is compared instead.",
            ),
        )
    return parts


def headline(analysis: Analysis, arm: str | None) -> list[str]:
    """The headline sentences of one arm (:func:`headline_parts` without their kinds)."""
    return [sentence for _, sentence in headline_parts(analysis, arm)]


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


ICC_WORDS = ((0.9, "excellent"), (0.75, "good"), (0.5, "moderate"), (float("-inf"), "poor"))
"""Agreement in words by ICC (Koo and Li 2016)."""


def icc_words(icc: float) -> str:
    """``good agreement (ICC 0.82)``, and for poor agreement what it means for a report."""
    word = next(w for bound, w in ICC_WORDS if icc >= bound)
    text = f"{word} agreement between patients' tests and retests (ICC {icc:.2f})"
    if word == "poor":
        text += ": the patients differ little against the measurement error, which is what the MDC95 judges by"
    return text


def error_source(analysis: Analysis) -> str:
    """Where the measurement error comes from, in one sentence."""
    judged = [s for s in analysis.series if s.judged and s.error.known]
    if not judged:
        return "No measurement error is known yet (no or too few retests): changes are not judged."
    error = judged[0].error
    whose = "this patient" if error.source == "subject" else f"{error.n_subjects} patients measured in this cell"
    iccs = sorted((s.error.icc, short_name(s.key)) for s in judged if s.error.icc is not None)
    if len(iccs) == 1:
        icc = f"; {icc_words(iccs[0][0])} for {iccs[0][1]}"
    elif iccs:
        (low, low_name), (high, high_name) = iccs[0], iccs[-1]
        icc = (
            f"; agreement between patients' tests and retests (ICC) from {low:.2f} ({low_name}, "
            f"{next(w for b, w in ICC_WORDS if low >= b)}) to {high:.2f} ({high_name}, "
            f"{next(w for b, w in ICC_WORDS if high >= b)}) over the {len(iccs)} quantities judged"
        )
    else:
        icc = ""
    return f"Measurement error (MDC95) from {error.n_pairs} same-day retests of {whose}{icc}."


def flag_rule(analysis: Analysis) -> str:
    """The rule that flags a change, in one plain sentence."""
    if not analysis.judgeable:
        return ""
    count = next((c.comparisons for s in analysis.series for c in s.steps), analysis.comparisons)
    return (
        "A step from one session to the next beyond the measurement error is a possible change, and a change once "
        "the next session, compared with the same earlier one, is beyond it too in the same direction; the limit "
        f"is set so that, over the {count} steps this report can confirm, an unchanged arm shows a change anywhere "
        "at most 1 time in 20 (friction, stiffness and damping compared as ratios)."
    )


def _difference(analysis: Analysis, untared: Untared, segment: str) -> tuple[float, str] | None:
    """The untared session's static moment of ``segment`` less the median of the arm's usable (tared) sessions, and
    its unit; None where either is missing."""
    key = ("segments", segment, "static_moment_kgm")
    quantity = untared.record.parameters.get(key)
    series = next((s for s in analysis.arm_series(untared.arm) if s.key == key), None)
    if quantity is None or quantity.value is None or series is None:
        return None
    values = [p.value for p in series.points if p.usable and p.value is not None]
    return (quantity.value - statistics.median(values), series.unit) if values else None


def weight_read(analysis: Analysis, untared: Untared) -> str:
    """What an untared session's static moments read against the tared sessions, shoulder to hand: in % where the
    tared median is clear of 0 (``+12 % (upper arm)``), else in units (``+0.021 kg·m (hand)``)."""
    percents = dict(untared.deviations)
    parts = []
    for segment in SEGMENT_ORDER:
        name = PART_NAMES.get(segment, segment).lower()
        if segment in percents:
            share = percents[segment]
            parts.append(f"{'+' if share > 0 else '−'}{percent(share)} ({name})")
            continue
        difference = _difference(analysis, untared, segment)
        if difference is not None:
            delta, unit_name = difference
            parts.append(f"{'+' if delta > 0 else '−'}{with_unit(abs(delta), unit_name)} ({name})")
    return ", ".join(parts)


def tare_sentences(analysis: Analysis) -> list[str]:
    """Page 1's sentence on each untared session among tared ones: what was left out, and why."""
    out = []
    for untared in analysis.untared:
        record = untared.record
        read = weight_read(analysis, untared)
        against = f": its arm weight read {read} against the tared sessions" if read else ""
        out.append(
            f"Session {untared.label} ({long_day(record.session_time_ns)}) was recorded without a tare (the sensor's "
            f"zero and the handle's weight){against}. The weight support and the arm-weight trend leave it out; its "
            "passive moments are used, their uncertainty including the unknown zero. Record a tare before every "
            "session (bsp sessions add … --tare FILE)."
        )
    return out


def invalid_cause(record: SessionRecord) -> tuple[str, str]:
    """Why a session could not be evaluated and what to do, in plain words: the cause and action of the estimator's
    first finding that made it invalid (a session stored without findings gives a general line)."""
    return plain_cause(record.quality.findings) or ("the measurement could not be evaluated", "repeat the session")


@dataclass(frozen=True)
class SessionRow:
    """One line of the session list (``retest``: a same-day retest, kept for the measurement error).

    ``number`` is the store's number of the session (``bsp sessions show``); ``label`` its name in the report
    (``3``, ``3a`` for the retest of session 3).
    """

    number: int
    date: str
    arm: str
    status: str
    attention: bool
    retest: bool = False
    label: str = ""

    @property
    def name(self) -> str:
        """The session's name in the report."""
        return self.label or str(self.number)


def _flagged_steps(analysis: Analysis, *, possible: bool = False) -> dict[int | None, list[str]]:
    """Each session's flagged steps (``possible``: possible changes) as ``elbow friction −25 %``, by session id."""
    flagged: dict[int | None, list[str]] = {}
    for series in analysis.series:
        found = ((series.possible,) if series.possible is not None else ()) if possible else series.changes
        for change in found:
            sign = "+" if change.delta > 0 else "−"
            flagged.setdefault(change.after.session_id, []).append(
                f"{short_name(series.key)} {sign}{_size(change, series.unit)}"
            )
    return flagged


def _status(
    analysis: Analysis,
    record: SessionRecord,
    flagged: dict[int | None, list[str]],
    possible: dict[int | None, list[str]],
) -> tuple[str, bool]:
    if not record.quality.valid:
        cause, action = invalid_cause(record)
        return f"Not usable: {cause}; {action}.", True
    if record.retest:
        return "Retest (for measurement error)", False
    parts, attention = [], False
    if record.id in flagged:
        parts.append(
            "Change beyond measurement error (confirmed by the next session): " + "; ".join(flagged[record.id])
        )
        attention = True
    if record.id in possible:
        parts.append("Possible change, to be confirmed by the next session: " + "; ".join(possible[record.id]))
        attention = True
    if any(u.record is record for u in analysis.untared):
        parts.append("No tare: its arm weight is left out")
        attention = True
    return ("; ".join(parts) if parts else "Usable"), attention


def session_rows(analysis: Analysis, *, retests: bool = True) -> list[SessionRow]:
    """The session list: only invalid sessions, untared ones among tared and flagged changes need attention.

    With ``retests`` False a retest has no line of its own: its name stands beside its session's status.
    """
    flagged, possible = _flagged_steps(analysis), _flagged_steps(analysis, possible=True)
    rows: list[SessionRow] = []
    for record in analysis.sessions:
        name = analysis.label_of(record)
        status, attention = _status(analysis, record, flagged, possible)
        visit = name.rstrip(RETEST_LETTERS)
        if record.retest and not retests and visit != name:
            partner = next((k for k in range(len(rows) - 1, -1, -1) if rows[k].label == visit), None)
            if partner is not None:
                rows[partner] = replace(rows[partner], status=f"{rows[partner].status} (retest {name})")
                continue
        arm = (record.arm or "–").capitalize()
        rows.append(
            SessionRow(record.number or 0, day(record.session_time_ns), arm, status, attention, record.retest, name)
        )
    return rows


def first_page_rows(rows: list[SessionRow], limit: int | None) -> tuple[list[SessionRow], str]:
    """The rows the first page lists, and a note on those left out (empty when all are listed).

    Every row that needs attention is listed (a flagged change on page 1 always has its line), and the baseline,
    the first usable session that changes "since the first session" are measured from; the latest sessions fill
    the rest up to ``limit``.
    """
    if limit is None or len(rows) <= limit:
        return rows, ""
    baseline = next((r for r in rows if not r.attention and not r.retest), rows[0])
    keep = {id(baseline)} | {id(r) for r in rows if r.attention}
    for row in reversed(rows):
        if len(keep) >= limit:
            break
        keep.add(id(row))
    shown = [r for r in rows if id(r) in keep]
    return shown, (
        f"The baseline (session {baseline.name}), every session that needs attention and the latest: {len(shown)} "
        f"of {len(rows)} sessions; all are listed in the detail."
    )


def _names(labels: list[str], every: int) -> str:
    if len(labels) == every and every > 1:
        return "Every session"
    return ("Session " if len(labels) == 1 else "Sessions ") + ", ".join(labels)


def session_notes(analysis: Analysis) -> list[tuple[str, str]]:
    """The clinic's notes on usable sessions: the plain cause and action of each finding that has one, once per
    session, identical notes of several sessions together, as ``(sessions, note)``; then each joint that resisted
    a fast stretch more than a slow one (:func:`speed_dependence_lines`)."""
    found: dict[str, list[str]] = {}
    for record in analysis.sessions:
        if not record.quality.valid:
            continue
        for finding in record.quality.findings:
            spec = finding.spec
            if finding.severity is Severity.INVALID or not spec.cause:
                continue
            where = PART_NAMES.get(finding.where, finding.where).lower()
            text = spec.cause.format(where=where) + (f": {spec.action}" if spec.action else "")
            labels = found.setdefault(text[0].upper() + text[1:], [])
            if analysis.label_of(record) not in labels:
                labels.append(analysis.label_of(record))
    every = sum(r.quality.valid for r in analysis.sessions)
    return [(_names(labels, every), text) for text, labels in found.items()] + speed_dependence_lines(analysis)


def technical_notes(analysis: Analysis) -> list[tuple[str, str]]:
    """The estimator's own texts for the engineer as ``(sessions, text)``: one line per kind of finding and part,
    with the sessions that have it and the latest one's text (numbers differ a little from session to session)."""
    found: dict[tuple[str, str], tuple[list[str], str]] = {}
    for record in analysis.sessions:
        name = analysis.label_of(record)
        items = [(str(f.code), f.where, f.text) for f in record.quality.findings]
        if not items:
            items = [("", text, text) for text in record.quality.warnings]
            if not record.quality.valid and record.quality.message:
                items.insert(0, ("", record.quality.message, record.quality.message))
        for code, where, text in items:
            labels, _ = found.get((code, where), ([], ""))
            if name not in labels:
                labels.append(name)
            found[(code, where)] = (labels, text)
    return [(_names(labels, len(analysis.sessions)), text) for labels, text in found.values()]


def tare_note(analysis: Analysis) -> str:
    """A sentence for the detail when no session was tared (each untared one among tared ones is on page 1)."""
    if any(r.quality.tare_applied for r in analysis.sessions):
        return ""
    return (
        "No session was recorded with a tare: the sensor's zero is assumed within its usual range (in each "
        "uncertainty) and a handle's weight would count as the arm's."
    )


@dataclass(frozen=True)
class SupportRow:
    """The support wrench at the reference pose for one support fraction."""

    fraction: float
    wrench_yzx: tuple[float, float, float]
    std_yzx: tuple[float, float, float]


def support_table(analysis: Analysis, arm: str | None) -> tuple[list[SupportRow], str]:
    """Support forces implied by the arm's latest usable static moments at :data:`REFERENCE_POSE_DEG`."""
    left_out = {id(u.record) for u in analysis.untared}
    latest = next((r for r in reversed(analysis.visits(arm)) if r.quality.valid and id(r) not in left_out), None)
    if latest is None:
        return [], "No usable session: no support settings can be derived."
    segments = [s for s in SEGMENT_ORDER if ("segments", s, "static_moment_kgm") in latest.parameters]
    beta = [latest.parameters[("segments", s, "static_moment_kgm")] for s in segments]
    lengths = [latest.parameters.get(("segments", s, "length_m")) for s in segments]
    if len(segments) < 2 or any(q.value is None for q in beta) or any(q is None or q.value is None for q in lengths):
        return (
            [],
            f"Session {analysis.label_of(latest)} lacks static moments or segment lengths: no support settings "
            "derived.",
        )
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
        f"From session {analysis.label_of(latest)} ({long_day(latest.session_time_ns)}), with the upper arm 45° below "
        "horizontal, the elbow at a right angle and the wrist straight: the force the robot applies at the handle "
        "(forward, upward) and the moment about the handle axis, so that it carries the given share of the "
        "arm's weight. Live, the robot computes it at the current pose."
    )
    return rows, note
