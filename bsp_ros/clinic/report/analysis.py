"""Per-arm, per-parameter trends across a subject's sessions, judged against the day-to-day measurement error."""

from __future__ import annotations

import itertools
import math
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

from bsp_ros.clinic.mdc import (
    DAY_NS,
    MIN_PAIRS,
    Z95,
    DayToDayError,
    ErrorScale,
    RetestPair,
    day_to_day_error,
    retest_pairs,
)
from bsp_ros.clinic.report.confirmation import confirmation_alpha
from bsp_ros.clinic.report.labels import label, sort_key, unit
from bsp_ros.clinic.report.priors import Prior, has_prior_inputs, session_prior
from bsp_ros.clinic.store.records import ParamKey, SessionRecord, SubjectRecord
from bsp_ros.errors import StoreError

NOT_JUDGED = ("offset_nm",)
NON_NEGATIVE = ("coulomb_nm", "stiffness_nm_per_rad", "viscous_nms")
"""Passive parameters the estimator bounds at 0: a value of exactly 0 means the data did not support it."""
"""Joint quantities shown but never judged: the elastic offset trades off against gravity (NOTES.md 1)."""


def is_judged(key: ParamKey) -> bool:
    """Whether changes of ``key`` are judged (flagged when beyond the MDC95): the passive joint moments.

    They are what therapy changes and what therapists watch. The static moments (the arm's weight) are shown
    with their MDC95 in the detail but not flagged: weeks of therapy do not change an arm's weight, so a
    difference there points at the setup, and flagging every measured quantity multiplies false alarms (each
    comparison at the 95 % level errs one time in twenty). Masses, centres of mass and lengths are derived or
    geometric; the elastic offset trades off against gravity.
    """
    group, _, quantity = key
    return group == "joints" and quantity not in NOT_JUDGED


def is_passive(key: ParamKey) -> bool:
    """A judged passive joint-moment parameter (what the first page shows)."""
    return is_judged(key)


@dataclass(frozen=True, kw_only=True)
class Point:
    """One session's estimate of one parameter.

    ``number`` is the session's number among the subject's sessions that are not retests (1 = first);
    ``valid`` False marks a session whose estimate is not usable: it is a gap, never a value in a trend or a
    comparison. ``left_out`` (non-empty) leaves a valid value out of the trend and its comparisons: an
    untared session's arm weight among tared sessions (:func:`untared_sessions`).
    """

    number: int
    session_id: int | None
    time_ns: int
    value: float | None
    std: float | None
    source: str
    valid: bool
    prior: Prior | None = None
    left_out: str = ""

    @property
    def usable(self) -> bool:
        """Valid, with a value and not left out (``left_out`` says why: an untared session's arm weight)."""
        return self.valid and self.value is not None and not self.left_out


MDC_SOURCES = ("retest pairs", "session uncertainty", "none")
"""What a change's MDC95 is: the retest pairs', the two sessions' own uncertainty where larger, or none."""


REPORT_ALPHA = 0.05
"""The chance, at most, that measurement error alone flags anything anywhere in one report (Bonferroni over its
confirmations: :mod:`bsp_ros.clinic.report.confirmation`)."""


def limit_factor(alpha: float, dof: int | None) -> float:
    """The two-sided ``1 - alpha`` quantile: Student's t for ``dof`` degrees of freedom, the normal for None."""
    from scipy.stats import norm, t

    return float(norm.ppf(1.0 - alpha / 2.0) if dof is None else t.ppf(1.0 - alpha / 2.0, dof))


@dataclass(frozen=True)
class Change:
    """The difference of one parameter between two usable sessions, against the day-to-day error.

    The change is judged on the error's scale (:class:`~bsp_ros.clinic.mdc.ErrorScale`): a positive passive
    parameter on the log scale (``ln(after / before)`` against the retest pairs' log-ratios and the estimates'
    relative uncertainty), any other in its unit. Every threshold (:attr:`mdc95`, :attr:`limit`) is given in the
    parameter's unit, back-transformed at the earlier value in the direction of the change, so that ``|delta|``
    exceeds it exactly where the change exceeds it on its scale.

    A step beyond :attr:`limit` is a possible change; it is a change (:attr:`flagged`) once ``confirmed_by``, the
    next usable session compared with the same earlier one, is beyond the same level in the same direction.
    ``comparisons`` is how many such confirmations the whole report judges: the level (:attr:`level`) keeps the
    chance of any false flag in the report at most :data:`REPORT_ALPHA`.
    """

    key: ParamKey
    before: Point
    after: Point
    delta: float
    error: DayToDayError
    comparisons: int = 1
    confirmed_by: Change | None = None

    @property
    def relative(self) -> bool:
        """Whether the change is judged on the log scale (its error is relative to the value)."""
        return self.error.scale is ErrorScale.LOG

    @property
    def scaled_delta(self) -> float | None:
        """The change on the error's scale: ``delta``, or ``ln(after / before)`` on the log scale (None there
        unless both values are positive)."""
        if not self.relative:
            return self.delta
        a, b = self.before.value, self.after.value
        if a is None or b is None or not (a > 0 and b > 0):
            return None
        return math.log(b / a)

    def in_unit(self, threshold: float | None) -> float | None:
        """A threshold on the error's scale as a change of the parameter from the earlier value, in its unit, in
        the direction of :attr:`delta` (a rise ``before (e^x - 1)``, a fall ``before (1 - e^-x)`` on the log
        scale); None for None or without a positive earlier value on the log scale."""
        if threshold is None or not self.relative:
            return threshold
        base = self.before.value
        if base is None or not base > 0:
            return None
        return base * (math.expm1(threshold) if self.delta > 0 else -math.expm1(-threshold))

    @property
    def mdc95(self) -> float | None:
        """The change two sessions must differ by to be more than measurement error (unit of the parameter, from
        the earlier value in the change's direction), None if unknown.

        The MDC95 from retest pairs; where the two estimates' own uncertainty is larger
        (1.96 sqrt(std_a^2 + std_b^2), relative stds on the log scale; e.g. a parameter the session could hardly
        determine), that. None without enough retest pairs: the estimates' own uncertainty alone never judges a
        change.
        """
        if self.error.mdc95 is None:
            return None
        return self.in_unit(max(self.error.mdc95, Z95 * self._own_sd))

    @property
    def own_mdc95(self) -> float:
        """The two estimates' own 95 % uncertainty of their difference, 1.96 sqrt(std_a^2 + std_b^2) (relative
        stds on the log scale), in the parameter's unit like :attr:`mdc95`."""
        return self.in_unit(Z95 * self._own_sd) or 0.0

    @property
    def _own_sd(self) -> float:
        """The two estimates' own sd of their difference on the error's scale (relative on the log scale)."""
        a, b = self.before, self.after
        if not self.relative:
            return math.hypot(a.std or 0.0, b.std or 0.0)
        if not (a.value and b.value and a.value > 0 and b.value > 0):
            return 0.0
        return math.hypot((a.std or 0.0) / a.value, (b.std or 0.0) / b.value)

    def _threshold(self, alpha: float) -> float | None:
        """The change on the error's scale beyond which this comparison is beyond measurement error at two-sided
        level ``alpha``: the retest pairs' SD of differences times Student's t for their number, or the two
        estimates' own SD times the normal quantile, whichever is larger. None without enough retest pairs."""
        if self.error.sem is None:
            return None
        retest = limit_factor(alpha, self.error.n_pairs) * self.error.sem * math.sqrt(2.0)
        return max(retest, limit_factor(alpha, None) * self._own_sd)

    def _beyond(self, threshold: float | None) -> bool:
        scaled = self.scaled_delta
        return threshold is not None and scaled is not None and not self.at_bound and abs(scaled) > threshold

    @property
    def level(self) -> float:
        """The two-sided per-comparison level of :attr:`limit` in a report of :attr:`comparisons` confirmations
        whose retest SD comes from the error's pairs
        (:func:`~bsp_ros.clinic.report.confirmation.confirmation_alpha`; unused where the error is unknown)."""
        return confirmation_alpha(max(self.comparisons, 1), max(self.error.n_pairs, 2), REPORT_ALPHA)

    @property
    def limit(self) -> float | None:
        """The change this comparison and its confirmation must each exceed to be flagged in a report of
        :attr:`comparisons` confirmations (unit of the parameter, from the earlier value in the change's
        direction).

        The MDC95 with its 95 % replaced by ``1 - level``: the retest pairs' SD of differences times Student's t
        for their number, or the two estimates' own SD times the normal quantile, whichever is larger. None
        without enough retest pairs.
        """
        return self.in_unit(self._threshold(self.level))

    @property
    def mdc95_source(self) -> str:
        """Where :attr:`mdc95` comes from: ``retest pairs``, ``session uncertainty`` (the two estimates' own,
        where larger) or ``none`` (too few retest pairs)."""
        if self.error.mdc95 is None:
            return MDC_SOURCES[2]
        return MDC_SOURCES[1] if Z95 * self._own_sd > self.error.mdc95 else MDC_SOURCES[0]

    @property
    def at_bound(self) -> bool:
        """Whether either value sits at the bound 0 of a non-negative passive parameter (not measured there), or
        a value on the log scale is not positive."""
        if self.key[2] in NON_NEGATIVE and (self.before.value == 0.0 or self.after.value == 0.0):
            return True
        return self.scaled_delta is None

    @property
    def judged(self) -> bool:
        """Whether this comparison is judged: the error is known and neither value sits at its bound."""
        return self.error.known and not self.at_bound

    @property
    def beyond_mdc(self) -> bool:
        """Whether the change exceeds the MDC95 of one comparison alone (not what flags: see :attr:`flagged`)."""
        if self.error.mdc95 is None:
            return False
        return self._beyond(max(self.error.mdc95, Z95 * self._own_sd))

    @property
    def possible(self) -> bool:
        """Whether the change exceeds :attr:`limit`: beyond measurement error unless the next session shows
        otherwise (a change once confirmed: :attr:`flagged`)."""
        return self.judged and self._beyond(self._threshold(self.level))

    @property
    def awaiting(self) -> bool:
        """A possible change the next session has not been recorded to confirm yet."""
        return self.possible and self.confirmed_by is None

    @property
    def flagged(self) -> bool:
        """Whether this is a change beyond measurement error over the whole report: :attr:`possible`, and the next
        usable session against the same earlier one (``confirmed_by``) beyond the same level in the same
        direction."""
        other = self.confirmed_by
        if other is None or not self.possible or not other.judged or other.delta * self.delta <= 0:
            return False
        return other._beyond(other._threshold(self.level))

    @property
    def percent(self) -> float | None:
        """The change in % of the earlier value; None where that is 0 or within 2 SD of 0 (a % of it means
        nothing)."""
        base = self.before.value
        if not base or abs(base) <= 2.0 * (self.before.std or 0.0):
            return None
        return 100.0 * self.delta / abs(base)

    @property
    def mdc_percent(self) -> float | None:
        """The MDC95 in % of the earlier value."""
        base, mdc = self.before.value, self.mdc95
        return None if not base or mdc is None else 100.0 * mdc / abs(base)

    @property
    def limit_percent(self) -> float | None:
        """The flag limit in % of the earlier value."""
        base, limit = self.before.value, self.limit
        return None if not base or limit is None else 100.0 * limit / abs(base)

    @property
    def mdc_ratio(self) -> float | None:
        """``|delta| / MDC95`` (None if the MDC is unknown)."""
        mdc = self.mdc95
        return None if not mdc else abs(self.delta) / mdc


@dataclass(frozen=True, kw_only=True)
class Series:
    """One parameter of one arm across the subject's sessions (retests left out), in time order.

    ``steps`` compares each usable session with the usable one before it; ``since_previous`` and
    ``since_first`` compare the latest usable session with the one before it and with the first.
    """

    arm: str | None
    key: ParamKey
    label: str
    unit: str
    points: tuple[Point, ...]
    error: DayToDayError
    judged: bool
    steps: tuple[Change, ...] = ()
    since_previous: Change | None = None
    since_first: Change | None = None

    @property
    def changes(self) -> tuple[Change, ...]:
        """Steps flagged: beyond the report's limit and confirmed by the next session (none for parameters that are
        not judged)."""
        return tuple(c for c in self.steps if c.flagged) if self.judged else ()

    @property
    def possible(self) -> Change | None:
        """The latest step where it is a possible change awaiting the next session's confirmation, else None."""
        latest = self.since_previous
        return latest if self.judged and latest is not None and latest.awaiting else None

    @property
    def has_values(self) -> bool:
        """Whether any usable session holds a value."""
        return any(p.usable for p in self.points)

    @property
    def has_prior(self) -> bool:
        """Whether any session has an anthropometric prior for this parameter."""
        return any(p.prior is not None for p in self.points)

    @property
    def latest(self) -> Point | None:
        """The latest usable point, else None."""
        return next((p for p in reversed(self.points) if p.usable), None)

    @property
    def flagged_latest(self) -> list[Change]:
        """The changes the latest usable session confirmed (the step before it, flagged)."""
        latest = self.latest
        return [c for c in self.changes if c.confirmed_by is not None and c.confirmed_by.after is latest]

    @property
    def comparisons(self) -> tuple[Change, ...]:
        """The confirmations of this series the report judges: each judged step with a judged confirmation."""
        if not self.judged:
            return ()
        return tuple(c for c in self.steps if c.judged and c.confirmed_by is not None and c.confirmed_by.judged)


@dataclass(frozen=True, kw_only=True)
class Analysis:
    """Everything a report shows about one subject."""

    subject: str
    record: SubjectRecord | None
    sessions: tuple[SessionRecord, ...]
    arms: tuple[str | None, ...]
    series: tuple[Series, ...]
    prior_note: str
    pairs: tuple[RetestPair, ...] = ()
    cell: str = ""
    min_pairs: int = MIN_PAIRS
    labels: tuple[str, ...] = ()
    untared: tuple[Untared, ...] = ()

    @property
    def comparisons(self) -> int:
        """How many confirmations the report judges (what each flag's level is set for)."""
        return sum(len(s.comparisons) for s in self.series)

    def label_of(self, record: SessionRecord) -> str:
        """The session's name in the report: ``3`` for the third session, ``3a`` for its same-day retest."""
        for k, known in enumerate(self.sessions):
            if known is record and k < len(self.labels):
                return self.labels[k]
        return str(record.number or "")

    def visits(self, arm: str | None) -> list[SessionRecord]:
        """The sessions of ``arm`` that make its trend (retests left out)."""
        return [r for r in self.sessions if r.arm == arm and not r.retest]

    def arm_series(self, arm: str | None) -> list[Series]:
        """Series of one arm, in display order."""
        return [s for s in self.series if s.arm == arm]

    @property
    def latest_changes(self) -> list[Change]:
        """Changes the latest usable session confirmed, every arm."""
        return [c for s in self.series for c in s.flagged_latest]

    @property
    def possible_changes(self) -> list[Change]:
        """Possible changes of the latest usable session, awaiting the next one, every arm."""
        return [c for s in self.series if (c := s.possible) is not None]

    @property
    def changes(self) -> list[Change]:
        """Every flagged step, in display order."""
        return [c for s in self.series for c in s.changes]

    @property
    def judgeable(self) -> bool:
        """Whether any judged parameter has a day-to-day error from enough retest pairs."""
        return any(s.judged and s.error.known for s in self.series)

    @property
    def own_pairs(self) -> int:
        """Retest pairs of this subject."""
        return sum(p.test.subject == self.subject for p in self.pairs)

    @property
    def cell_pairs(self) -> int:
        """Retest pairs of every subject of this subject's cell."""
        return sum(p.test.cell == self.cell for p in self.pairs)


def _merge_subject(record: SessionRecord, subject: SubjectRecord | None) -> SessionRecord:
    if subject is None or not subject.body():
        return record
    return replace(record, subject_info={**record.subject_info, **subject.body()})


def _compare(key: ParamKey, before: Point, after: Point, error: DayToDayError) -> Change:
    assert before.value is not None and after.value is not None
    return Change(key, before, after, after.value - before.value, error)


WEIGHT_QUANTITIES = ("static_moment_kgm", "mass_kg", "com_m", "first_moment_kgm")
"""What a forgotten tare moves: the arm's weight and what is fused from it (the sensor's zero and the handle's
weight load the static moments; the masses and centres of mass are combined from them)."""


@dataclass(frozen=True)
class Untared:
    """A valid session recorded without a tare among an arm's tared sessions: its arm weight is left out.

    ``deviations`` are its static moments' differences from the median of the arm's tared sessions, in %
    (segment, %), where that median is clear of 0.
    """

    arm: str | None
    record: SessionRecord
    label: str
    deviations: tuple[tuple[str, float], ...]


RETEST_LETTERS = "abcdefghijklmnopqrstuvwxyz"


def visit_labels(sessions: Sequence[SessionRecord]) -> tuple[str, ...]:
    """Each session's name: visits numbered 1..n in time order, a retest its visit's number and a letter.

    A retest belongs to the latest earlier session of the same arm and day that is not a retest (``3a``,
    ``3b``); one without such a session is numbered as a visit.
    """
    labels: list[str] = []
    visits = 0
    letters: dict[int, int] = {}
    for k, record in enumerate(sessions):
        partner = None
        if record.retest:
            day = record.session_time_ns // DAY_NS
            partner = next(
                (
                    j
                    for j in range(k - 1, -1, -1)
                    if not sessions[j].retest
                    and sessions[j].arm == record.arm
                    and sessions[j].session_time_ns // DAY_NS == day
                ),
                None,
            )
        if partner is None:
            visits += 1
            labels.append(str(visits))
        else:
            letters[partner] = letters.get(partner, 0) + 1
            labels.append(labels[partner] + RETEST_LETTERS[min(letters[partner], 26) - 1])
    return tuple(labels)


def untared_sessions(sessions: Sequence[SessionRecord], labels: Sequence[str]) -> tuple[Untared, ...]:
    """The valid untared visits of every arm that also has valid tared visits (see :class:`Untared`)."""
    found = []
    for arm in dict.fromkeys(r.arm for r in sessions):
        visits = [(r, lab) for r, lab in zip(sessions, labels, strict=True) if r.arm == arm and not r.retest]
        valid = [(r, lab) for r, lab in visits if r.quality.valid]
        tared = [r for r, _ in valid if r.quality.tare_applied]
        if not tared:
            continue
        for record, lab in valid:
            if not record.quality.tare_applied:
                found.append(Untared(arm, record, lab, tuple(_deviations(record, tared))))
    return tuple(found)


def _deviations(record: SessionRecord, tared: Sequence[SessionRecord]) -> list[tuple[str, float]]:
    import statistics

    found = []
    for group, segment, quantity in record.parameters:
        if group != "segments" or quantity != "static_moment_kgm":
            continue
        key = (group, segment, quantity)
        value = record.parameters[key].value
        values = [r.parameters[key] for r in tared if key in r.parameters and r.parameters[key].value is not None]
        if value is None or not values:
            continue
        median = statistics.median(q.value or 0.0 for q in values)
        spread = statistics.median(q.std or 0.0 for q in values)
        if abs(median) > 2.0 * spread:
            found.append((segment, 100.0 * (value - median) / abs(median)))
    return found


def _points(key: ParamKey, visits: Sequence[tuple[SessionRecord, str]], left_out: frozenset[int]) -> tuple[Point, ...]:
    weight = key[0] == "segments" and key[2] in WEIGHT_QUANTITIES
    return tuple(
        Point(
            number=int(lab),
            session_id=r.id,
            time_ns=r.session_time_ns,
            value=r.parameters[key].value,
            std=r.parameters[key].std,
            source=r.parameters[key].source,
            valid=r.quality.valid,
            prior=session_prior(r, key),
            left_out="recorded without a tare" if weight and id(r) in left_out else "",
        )
        for r, lab in visits
        if key in r.parameters
    )


def _arm_series(
    arm: str | None,
    visits: Sequence[tuple[SessionRecord, str]],
    errors: Callable[[ParamKey], DayToDayError],
    left_out: frozenset[int],
) -> list[Series]:
    series = []
    for key in sorted({key for r, _ in visits for key in r.parameters}, key=sort_key):
        error = errors(key)
        points = _points(key, visits, left_out)
        usable = [p for p in points if p.usable]
        steps = tuple(
            replace(_compare(key, a, b, error), confirmed_by=_compare(key, a, usable[k + 2], error))
            if k + 2 < len(usable)
            else _compare(key, a, b, error)
            for k, (a, b) in enumerate(itertools.pairwise(usable))
        )
        first = _compare(key, usable[0], usable[-1], error) if len(usable) >= 3 else None
        series.append(
            Series(
                arm=arm,
                key=key,
                label=label(key),
                unit=unit(key[2]),
                points=points,
                error=error,
                judged=is_judged(key),
                steps=steps,
                since_previous=steps[-1] if steps else None,
                since_first=first,
            )
        )
    return series


def _widened(series: Sequence[Series]) -> tuple[Series, ...]:
    """``series`` with every comparison told how many confirmations the report judges (the level of its flags).

    At least as many as the judged series' latest steps, which the next session will confirm: a report of two or
    three sessions, with few confirmations or none, would otherwise call possible changes at a loose level.
    """
    latest = sum(1 for s in series if s.judged and s.steps and s.steps[-1].judged)
    count = max(sum(len(s.comparisons) for s in series), latest)
    out = []
    for s in series:
        steps = tuple(replace(c, comparisons=count) for c in s.steps)
        first = replace(s.since_first, comparisons=count) if s.since_first is not None else None
        out.append(replace(s, steps=steps, since_previous=steps[-1] if steps else None, since_first=first))
    return tuple(out)


def analyse(
    subject: str,
    records: Sequence[SessionRecord],
    *,
    pool: Sequence[SessionRecord] | None = None,
    subject_record: SubjectRecord | None = None,
    min_pairs: int = MIN_PAIRS,
) -> Analysis:
    """Build the per-arm series of ``subject``'s sessions and judge their changes against retest pairs.

    Each step between usable sessions of every judged parameter is a possible change beyond a limit set for the
    report's number of confirmations (:attr:`Change.limit`), and flagged when the next session confirms it, so that
    an unchanged arm is flagged anywhere in the report at most 1 time in 20. An untared session among an arm's
    tared ones keeps its passive moments but not its arm weight (:func:`untared_sessions`).

    Parameters
    ----------
    subject : str
        The pseudonymous subject id.
    records : sequence of SessionRecord
        The subject's sessions (any order; sorted by time here), retests included.
    pool : sequence of SessionRecord, optional
        Every session of the store: retest pairs of the subject's cell are pooled from it while the subject
        has fewer than ``min_pairs`` of its own. Default: ``records``.
    subject_record : SubjectRecord, optional
        Body data and arms; its body data replace the sessions' for the priors.
    min_pairs : int
        Fewer retest pairs give no MDC: changes are then not judged.

    Raises
    ------
    StoreError
        If there are no sessions.
    """
    if not records:
        raise StoreError(f"no sessions of subject {subject} to report")
    sessions = tuple(
        _merge_subject(r, subject_record) for r in sorted(records, key=lambda r: (r.session_time_ns, r.id or 0))
    )
    labels = visit_labels(sessions)
    untared = untared_sessions(sessions, labels)
    left_out = frozenset(id(u.record) for u in untared)
    pairs = tuple(retest_pairs(pool if pool is not None else records))
    cell = Counter(r.cell for r in sessions).most_common(1)[0][0]
    preferred = subject_record.arm if subject_record is not None else None
    present = list(dict.fromkeys(r.arm for r in sessions))
    arms = tuple(sorted(present, key=lambda a: (a != preferred, a is None, a or "")))
    series: list[Series] = []
    for arm in arms:
        visits = [(r, lab) for r, lab in zip(sessions, labels, strict=True) if r.arm == arm and not r.retest]
        series += _arm_series(arm, visits, lambda key: day_to_day_error(key, subject, cell, pairs, min_pairs), left_out)
    return Analysis(
        subject=subject,
        record=subject_record,
        sessions=sessions,
        arms=arms,
        series=_widened(series),
        prior_note=_prior_note(sessions),
        pairs=pairs,
        cell=cell,
        min_pairs=min_pairs,
        labels=labels,
        untared=untared,
    )


def _prior_note(sessions: Sequence[SessionRecord]) -> str:
    with_inputs = sum(has_prior_inputs(r) for r in sessions)
    if with_inputs == 0:
        return (
            "No table range is shown: the subject's body mass and sex are not recorded "
            "(set them once with bsp subjects set)."
        )
    text = (
        "Grey bands show the typical range (±2 SD) of segment mass and centre of mass for this subject's body "
        "mass and sex from anthropometric tables (de Leva 1996); individuals often differ from tables."
    )
    if with_inputs < len(sessions):
        text += f" Only {with_inputs} of {len(sessions)} sessions record body mass and sex."
    return text
