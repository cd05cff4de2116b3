"""Per-arm, per-parameter trends across a subject's sessions, judged against the day-to-day measurement error."""

from __future__ import annotations

import itertools
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, replace

from bsp_ros.clinic.mdc import MIN_PAIRS, Z95, DayToDayError, RetestPair, day_to_day_error, retest_pairs
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


@dataclass(frozen=True)
class Point:
    """One session's estimate of one parameter.

    ``number`` is the session's number within the subject (1 = first); ``valid`` False marks a session whose
    estimate is not usable: it is a gap, never a value in a trend or a comparison.
    """

    number: int
    session_id: int | None
    time_ns: int
    value: float | None
    std: float | None
    source: str
    valid: bool
    prior: Prior | None = None

    @property
    def usable(self) -> bool:
        """Valid and with a value."""
        return self.valid and self.value is not None


MDC_SOURCES = ("retest pairs", "session uncertainty", "none")
"""What a change's MDC95 is: the retest pairs', the two sessions' own uncertainty where larger, or none."""


@dataclass(frozen=True)
class Change:
    """The difference of one parameter between two usable sessions, against the day-to-day error."""

    key: ParamKey
    before: Point
    after: Point
    delta: float
    error: DayToDayError

    @property
    def mdc95(self) -> float | None:
        """The change two sessions must differ by to be more than measurement error, None if unknown.

        The MDC95 from retest pairs; where the two estimates' own uncertainty is larger
        (1.96 sqrt(std_a^2 + std_b^2), e.g. a parameter the session could hardly determine), that. None
        without enough retest pairs: the estimates' own uncertainty alone never judges a change.
        """
        if self.error.mdc95 is None:
            return None
        return max(self.error.mdc95, self.own_mdc95)

    @property
    def own_mdc95(self) -> float:
        """The two estimates' own 95 % uncertainty of their difference, 1.96 sqrt(std_a^2 + std_b^2)."""
        return Z95 * math.hypot(self.before.std or 0.0, self.after.std or 0.0)

    @property
    def mdc95_source(self) -> str:
        """Where :attr:`mdc95` comes from: ``retest pairs``, ``session uncertainty`` (the two estimates' own,
        where larger) or ``none`` (too few retest pairs)."""
        if self.error.mdc95 is None:
            return MDC_SOURCES[2]
        return MDC_SOURCES[1] if self.own_mdc95 > self.error.mdc95 else MDC_SOURCES[0]

    @property
    def at_bound(self) -> bool:
        """Whether either value sits at the bound 0 of a non-negative passive parameter (not measured there)."""
        return self.key[2] in NON_NEGATIVE and (self.before.value == 0.0 or self.after.value == 0.0)

    @property
    def beyond_mdc(self) -> bool:
        """Whether ``|delta|`` exceeds the MDC95 (False when the MDC is unknown: no change can be claimed)."""
        return self.mdc95 is not None and not self.at_bound and abs(self.delta) > self.mdc95

    @property
    def percent(self) -> float | None:
        """The change in % of the earlier value (None if that is 0)."""
        base = self.before.value
        return None if not base else 100.0 * self.delta / abs(base)

    @property
    def mdc_percent(self) -> float | None:
        """The MDC95 in % of the earlier value."""
        base = self.before.value
        return None if not base or self.mdc95 is None else 100.0 * self.mdc95 / abs(base)

    @property
    def mdc_ratio(self) -> float | None:
        """``|delta| / MDC95`` (None if the MDC is unknown)."""
        return None if not self.mdc95 else abs(self.delta) / self.mdc95


@dataclass(frozen=True)
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
        """Steps beyond the MDC95 (none for parameters that are not judged)."""
        return tuple(c for c in self.steps if c.beyond_mdc) if self.judged else ()

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
        """The latest session's comparisons (since previous, since first) beyond the MDC95."""
        if not self.judged:
            return []
        return [c for c in (self.since_previous, self.since_first) if c is not None and c.beyond_mdc]


@dataclass(frozen=True)
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

    def visits(self, arm: str | None) -> list[SessionRecord]:
        """The sessions of ``arm`` that make its trend (retests left out)."""
        return [r for r in self.sessions if r.arm == arm and not r.retest]

    def arm_series(self, arm: str | None) -> list[Series]:
        """Series of one arm, in display order."""
        return [s for s in self.series if s.arm == arm]

    @property
    def latest_changes(self) -> list[Change]:
        """Changes of the latest usable session beyond the MDC95 (since previous and since first), every arm."""
        return [c for s in self.series for c in s.flagged_latest]

    @property
    def changes(self) -> list[Change]:
        """Every step beyond the MDC95, in display order."""
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


def analyse(
    subject: str,
    records: Sequence[SessionRecord],
    *,
    pool: Sequence[SessionRecord] | None = None,
    subject_record: SubjectRecord | None = None,
    min_pairs: int = MIN_PAIRS,
) -> Analysis:
    """Build the per-arm series of ``subject``'s sessions and judge their changes against retest pairs.

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
    pairs = tuple(retest_pairs(pool if pool is not None else records))
    cells = Counter(r.cell for r in sessions)
    cell = cells.most_common(1)[0][0]
    preferred = subject_record.arm if subject_record is not None else None
    present = list(dict.fromkeys(r.arm for r in sessions))
    arms = tuple(sorted(present, key=lambda a: (a != preferred, a is None, a or "")))
    series = []
    for arm in arms:
        visits = [r for r in sessions if r.arm == arm and not r.retest]
        keys = sorted({key for r in visits for key in r.parameters}, key=sort_key)
        for key in keys:
            error = day_to_day_error(key, subject, cell, pairs, min_pairs)
            points = tuple(
                Point(
                    r.number or 0,
                    r.id,
                    r.session_time_ns,
                    r.parameters[key].value,
                    r.parameters[key].std,
                    r.parameters[key].source,
                    r.quality.valid,
                    session_prior(r, key),
                )
                for r in visits
                if key in r.parameters
            )
            usable = [p for p in points if p.usable]
            steps = tuple(_compare(key, a, b, error) for a, b in itertools.pairwise(usable))
            series.append(
                Series(
                    arm,
                    key,
                    label(key),
                    unit(key[2]),
                    points,
                    error,
                    is_judged(key),
                    steps,
                    steps[-1] if steps else None,
                    _compare(key, usable[0], usable[-1], error) if len(usable) >= 3 else None,
                )
            )
    return Analysis(
        subject, subject_record, sessions, arms, tuple(series), _prior_note(sessions), pairs, cell, min_pairs
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
