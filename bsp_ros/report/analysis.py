"""Per-parameter trends across a subject's sessions, and changes larger than their uncertainties explain."""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

from bsp_ros.errors import StoreError
from bsp_ros.report.labels import label, sort_key, unit
from bsp_ros.report.priors import Prior, has_prior_inputs, session_prior
from bsp_ros.store.records import ParamKey, SessionRecord

CHANGE_SIGMAS = 3.0
"""A change between consecutive sessions is flagged when ``|d| > CHANGE_SIGMAS * sqrt(s1**2 + s2**2)``."""


@dataclass(frozen=True)
class Point:
    """One session's estimate of one parameter."""

    session_id: int | None
    time_ns: int
    value: float | None
    std: float | None
    source: str
    valid: bool
    prior: Prior | None


@dataclass(frozen=True)
class Change:
    """A change between consecutive sessions that the uncertainties do not explain."""

    key: ParamKey
    before: Point
    after: Point
    delta: float
    combined_std: float

    @property
    def sigmas(self) -> float:
        """``|delta|`` in units of the combined standard deviation (inf if both stds are 0)."""
        return abs(self.delta) / self.combined_std if self.combined_std > 0 else math.inf


@dataclass(frozen=True)
class Series:
    """One parameter across sessions, in time order."""

    key: ParamKey
    label: str
    unit: str
    points: tuple[Point, ...]
    changes: tuple[Change, ...]

    @property
    def has_values(self) -> bool:
        """Whether any session holds a finite value."""
        return any(p.value is not None for p in self.points)

    @property
    def has_prior(self) -> bool:
        """Whether any session has an anthropometric prior for this parameter."""
        return any(p.prior is not None for p in self.points)


@dataclass(frozen=True)
class Analysis:
    """Everything a report shows about one subject."""

    subject: str
    sessions: tuple[SessionRecord, ...]
    series: tuple[Series, ...]
    prior_note: str

    @property
    def changes(self) -> list[Change]:
        """Every flagged change, in display order of the parameters."""
        return [c for s in self.series for c in s.changes]


def flag_changes(key: ParamKey, points: Sequence[Point], sigmas: float = CHANGE_SIGMAS) -> list[Change]:
    """Changes between consecutive sessions (with values and stds) beyond ``sigmas`` combined stds."""
    usable = [p for p in points if p.value is not None and p.std is not None]
    changes = []
    for before, after in itertools.pairwise(usable):
        assert before.value is not None and after.value is not None
        assert before.std is not None and after.std is not None
        delta = after.value - before.value
        combined = math.hypot(before.std, after.std)
        if abs(delta) > sigmas * combined:
            changes.append(Change(key, before, after, delta, combined))
    return changes


def analyse(subject: str, records: Sequence[SessionRecord]) -> Analysis:
    """Build the per-parameter series, priors and change flags of ``subject``'s sessions.

    Parameters
    ----------
    subject : str
        The pseudonymous subject id.
    records : sequence of SessionRecord
        The subject's sessions (any order; sorted by time here).

    Returns
    -------
    Analysis
        Series in display order.

    Raises
    ------
    StoreError
        If there are no sessions.
    """
    if not records:
        raise StoreError(f"no sessions of subject {subject} to report")
    sessions = tuple(sorted(records, key=lambda r: (r.session_time_ns, r.id or 0)))
    keys = sorted({key for r in sessions for key in r.parameters}, key=sort_key)
    series = []
    for key in keys:
        points = tuple(
            Point(
                r.id,
                r.session_time_ns,
                r.parameters[key].value,
                r.parameters[key].std,
                r.parameters[key].source,
                r.quality.valid,
                session_prior(r, key),
            )
            for r in sessions
            if key in r.parameters
        )
        series.append(Series(key, label(key), unit(key[2]), points, tuple(flag_changes(key, points))))
    return Analysis(subject, sessions, tuple(series), _prior_note(sessions))


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
