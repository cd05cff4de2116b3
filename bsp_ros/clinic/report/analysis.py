"""Per-parameter trends across a subject's sessions, and changes beyond the minimal detectable change (MDC95)."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

from bsp_ros.clinic.mdc import BASELINE_METHOD, baseline_sem, pair_mdc95, sem_of
from bsp_ros.clinic.report.labels import label, sort_key, unit
from bsp_ros.clinic.report.priors import Prior, has_prior_inputs, session_prior
from bsp_ros.clinic.store.records import ParamKey, SessionRecord
from bsp_ros.errors import InputError, StoreError


@dataclass(frozen=True)
class Point:
    """One session's estimate of one parameter.

    ``sem`` is the standard error of measurement used for MDCs (the session's cycle-to-cycle SEM, or the
    baseline sessions' if larger), None if neither is known.
    """

    session_id: int | None
    time_ns: int
    value: float | None
    std: float | None
    source: str
    valid: bool
    prior: Prior | None
    sem: float | None = None


@dataclass(frozen=True)
class Change:
    """The difference of one parameter between two valid sessions, against their MDC95."""

    key: ParamKey
    before: Point
    after: Point
    delta: float
    mdc95: float | None

    @property
    def beyond_mdc(self) -> bool:
        """Whether ``|delta|`` exceeds the MDC95 (False when the MDC is unknown: no change can be claimed)."""
        return self.mdc95 is not None and abs(self.delta) > self.mdc95

    @property
    def mdc_ratio(self) -> float | None:
        """``|delta| / MDC95`` (None if the MDC is unknown, inf if it is 0)."""
        if self.mdc95 is None:
            return None
        return abs(self.delta) / self.mdc95 if self.mdc95 > 0 else math.inf


@dataclass(frozen=True)
class Series:
    """One parameter across sessions, in time order.

    ``changes`` are consecutive valid sessions that differ beyond their MDC95; ``since_previous`` and
    ``since_first`` compare the latest valid session with the one before it and with the first valid one.
    """

    key: ParamKey
    label: str
    unit: str
    points: tuple[Point, ...]
    changes: tuple[Change, ...]
    since_previous: Change | None = None
    since_first: Change | None = None

    @property
    def has_values(self) -> bool:
        """Whether any session holds a finite value."""
        return any(p.value is not None for p in self.points)

    @property
    def has_prior(self) -> bool:
        """Whether any session has an anthropometric prior for this parameter."""
        return any(p.prior is not None for p in self.points)

    @property
    def latest(self) -> Point | None:
        """The latest valid session's point with a value, else None."""
        return next((p for p in reversed(self.points) if p.valid and p.value is not None), None)


@dataclass(frozen=True)
class Analysis:
    """Everything a report shows about one subject."""

    subject: str
    sessions: tuple[SessionRecord, ...]
    series: tuple[Series, ...]
    prior_note: str
    baseline_sessions: int = 0

    @property
    def changes(self) -> list[Change]:
        """Every change between consecutive valid sessions beyond the MDC95, in display order."""
        return [c for s in self.series for c in s.changes]

    @property
    def latest_changes(self) -> list[Change]:
        """Changes of the latest valid session beyond the MDC95, since the previous and since the first."""
        found = []
        for s in self.series:
            for change in (s.since_previous, s.since_first):
                if change is not None and change.beyond_mdc:
                    found.append(change)
        return found

    @property
    def methods(self) -> list[str]:
        """How the SEMs behind the MDCs were obtained (distinct texts, in session order)."""
        texts = [str(r.repeatability.get("method")) for r in self.sessions if r.repeatability.get("method")]
        if self.baseline_sessions >= 2:
            texts.append(BASELINE_METHOD)
        return list(dict.fromkeys(texts))


def compare(key: ParamKey, before: Point, after: Point) -> Change:
    """The change from ``before`` to ``after`` (both with values) and its MDC95 = 1.96 sqrt(SEM_a^2 + SEM_b^2)."""
    assert before.value is not None and after.value is not None
    mdc = None if before.sem is None or after.sem is None else pair_mdc95(before.sem, after.sem)
    return Change(key, before, after, after.value - before.value, mdc)


def flag_changes(key: ParamKey, points: Sequence[Point]) -> list[Change]:
    """Changes between consecutive valid sessions (with values) beyond their MDC95."""
    usable = [p for p in points if p.valid and p.value is not None]
    changes = [compare(key, before, after) for before, after in itertools.pairwise(usable)]
    return [c for c in changes if c.beyond_mdc]


def _group_key(key: ParamKey) -> str:
    return ".".join(key)


def analyse(subject: str, records: Sequence[SessionRecord], baseline_sessions: int = 0) -> Analysis:
    """Build the per-parameter series, priors, SEMs and changes beyond the MDC of ``subject``'s sessions.

    Parameters
    ----------
    subject : str
        The pseudonymous subject id.
    records : sequence of SessionRecord
        The subject's sessions (any order; sorted by time here).
    baseline_sessions : int
        The first this many valid sessions are test-retest baseline sessions (0 or >= 2): their
        successive-difference SEM is used where it exceeds a session's own cycle-to-cycle SEM.

    Returns
    -------
    Analysis
        Series in display order.

    Raises
    ------
    StoreError
        If there are no sessions.
    InputError
        If ``baseline_sessions`` is 1 or negative.
    """
    if not records:
        raise StoreError(f"no sessions of subject {subject} to report")
    if baseline_sessions < 0 or baseline_sessions == 1:
        raise InputError(f"baseline sessions must be 0 (none) or at least 2, got {baseline_sessions}")
    sessions = tuple(sorted(records, key=lambda r: (r.session_time_ns, r.id or 0)))
    keys = sorted({key for r in sessions for key in r.parameters}, key=sort_key)
    series = []
    for key in keys:
        path = _group_key(key)
        chosen = [r for r in sessions if key in r.parameters]
        baseline = [r.parameters[key].value for r in chosen if r.quality.valid][:baseline_sessions]
        base_sem = baseline_sem(baseline) if baseline_sessions >= 2 else math.nan
        points = []
        for r in chosen:
            q = r.parameters[key]
            known = [s for s in (sem_of(r.repeatability, path), base_sem) if s is not None and math.isfinite(s)]
            points.append(
                Point(
                    r.id,
                    r.session_time_ns,
                    q.value,
                    q.std,
                    q.source,
                    r.quality.valid,
                    session_prior(r, key),
                    max(known) if known else None,
                )
            )
        usable = [p for p in points if p.valid and p.value is not None]
        since_previous = compare(key, usable[-2], usable[-1]) if len(usable) >= 2 else None
        since_first = compare(key, usable[0], usable[-1]) if len(usable) >= 3 else None
        series.append(
            Series(
                key,
                label(key),
                unit(key[2]),
                tuple(points),
                tuple(flag_changes(key, points)),
                since_previous,
                since_first,
            )
        )
    return Analysis(subject, sessions, tuple(series), _prior_note(sessions), baseline_sessions)


def _prior_note(sessions: Sequence[SessionRecord]) -> str:
    with_inputs = sum(has_prior_inputs(r) for r in sessions)
    if with_inputs == 0:
        return (
            "No anthropometric reference band is shown: the sessions do not record the subject's body mass "
            "and sex, which the tables (de Leva 1996) need."
        )
    text = (
        "Grey bands show the typical range (±2 SD) of segment mass and centre of mass for this subject's body "
        "mass and sex from anthropometric tables (de Leva 1996); individuals often differ from tables."
    )
    if with_inputs < len(sessions):
        text += f" Only {with_inputs} of {len(sessions)} sessions record body mass and sex."
    return text
