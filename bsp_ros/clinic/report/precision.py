"""How precise the latest usable session's numbers are, and what would make them more precise: each quantity's
uncertainty budget (docs/contract.md, ``budget``), its largest term in plain words and that term's remedy."""

from __future__ import annotations

import math
from dataclasses import dataclass

from bsp_ros.clinic.report.analysis import WEIGHT_QUANTITIES, Analysis
from bsp_ros.clinic.report.detail import PASSIVE
from bsp_ros.clinic.report.labels import plain_name, sort_key, unit, with_unit
from bsp_ros.clinic.report.summary import percent
from bsp_ros.clinic.report.term_words import engineer_remedy, term_remedy, term_words
from bsp_ros.clinic.store.records import ParamKey, SessionRecord

CLINICIAN_QUANTITIES = ("static_moment_kgm", *PASSIVE)
"""What the clinician's part shows: the static moments and the passive moments (the appendix shows every
quantity with a budget)."""

PRECISION_TITLE = "How precise the latest session is"
PRECISION_NOTE = (
    "Each number's uncertainty (1 SD) is the sum of named sources, each with its share of the variance; the "
    "largest is named with what would shrink it at the next session."
)
BUDGET_TITLE = "Uncertainty budget of the latest session"
BUDGET_NOTE = (
    "Each term's standard uncertainty (its share of the variance): their squares sum to the SD's square "
    "(docs/method.md, the uncertainty budget). The remedy is the estimator's own (Term.remedy)."
)


@dataclass(frozen=True, kw_only=True)
class Precision:
    """One quantity of one arm's latest usable session with its uncertainty budget.

    Attributes
    ----------
    arm : the measured arm, None where not recorded.
    session : the session's name in the report (``6``).
    time_ns : the session's start, ns since the epoch.
    key : ``(group, part, quantity)``.
    value, std : the estimate and its standard deviation, in the unit of ``key``.
    terms : ``(term, standard uncertainty)`` of the budget, largest first; the squares sum to ``std`` squared.
    tared : whether the session was recorded with a tare.
    left_out : why the report leaves this value out of the trend and the weight support (an untared session's arm
        weight among tared sessions), ``""`` where it is used.
    """

    arm: str | None
    session: str
    time_ns: int
    key: ParamKey
    value: float | None
    std: float
    terms: tuple[tuple[str, float], ...]
    tared: bool
    left_out: str = ""

    @property
    def largest(self) -> tuple[str, float]:
        """The largest term and its share of the variance (0-1)."""
        term, u = self.terms[0]
        return term, u**2 / self.std**2

    def share(self, u: float) -> float:
        """A term's share of the variance (0-1), of its standard uncertainty ``u``."""
        return u**2 / self.std**2

    @property
    def name(self) -> str:
        """The parameter's plain name, capitalised."""
        name = plain_name(self.key)
        return name[0].upper() + name[1:]

    @property
    def latest(self) -> str:
        """``0.61 ± 0.032 kg·m (± 5 %)``; the % only where the value is clear of 2 SD of 0; a value the report leaves
        out says so (``…; not used: recorded without a tare …``)."""
        text = f"{with_unit(self.value, '')} ± {with_unit(self.std, unit(self.key[2]))}"
        if self.value is not None and abs(self.value) > 2.0 * self.std:
            text += f" (± {percent(100.0 * self.std / abs(self.value))})"
        return text + (f"; not used: {self.left_out}" if self.left_out else "")

    @property
    def words(self) -> str:
        """The largest term in plain words and its share: ``the force sensor's zero (no tare), 71 %``."""
        term, share = self.largest
        return f"{term_words(term, tared=self.tared)}, {percent(100.0 * share)}"

    @property
    def remedy(self) -> str:
        """What would shrink the largest term, in the clinic's words (``""`` for a term this version lacks)."""
        return term_remedy(self.largest[0], tared=self.tared)

    @property
    def budget_text(self) -> str:
        """Every term for the engineer: ``sensor_zero 0.027 (71 %); marker_placement 0.015 (22 %)`` (a term of
        exactly 0 left out: it is no source of this quantity's uncertainty)."""
        shown = [(term, u) for term, u in self.terms if u > 0.0]
        return "; ".join(f"{term} {with_unit(u, '')} ({percent(100.0 * self.share(u))})" for term, u in shown)

    @property
    def engineer_remedy(self) -> str:
        """The estimator's phrase for what shrinks the largest term."""
        return engineer_remedy(self.largest[0])


def latest_usable(analysis: Analysis, arm: str | None) -> tuple[SessionRecord, str] | None:
    """The arm's latest valid visit (retests left out) and its name in the report, None without one."""
    found = None
    for record in analysis.visits(arm):
        if record.quality.valid:
            found = record
    return None if found is None else (found, analysis.label_of(found))


UNTARED_LEFT_OUT = (
    "recorded without a tare among tared sessions, this arm weight is left out of the trend and the weight support"
)


def precision_of(record: SessionRecord, name: str, key: ParamKey, *, left_out: str = "") -> Precision | None:
    """The budget of ``key`` in ``record``; None where the store holds none (sessions stored before budgets, the
    paper's method) or the std is not a positive number. ``left_out``: see :class:`Precision`."""
    q = record.parameters.get(key)
    if q is None or q.budget is None or q.std is None or not q.std > 0.0 or not math.isfinite(q.std):
        return None
    terms = tuple(sorted(((t, u) for t, u in q.budget.items() if u is not None), key=lambda pair: -pair[1]))
    if not terms:
        return None
    return Precision(
        arm=record.arm,
        session=name,
        time_ns=record.session_time_ns,
        key=key,
        value=q.value,
        std=q.std,
        terms=terms,
        tared=record.quality.tare_applied,
        left_out=left_out,
    )


def precision_rows(analysis: Analysis, *, clinician: bool) -> list[Precision]:
    """Each arm's latest usable session's quantities with a budget, in display order; the arm weight of an untared
    session among tared ones labelled as left out (:attr:`Precision.left_out`).

    Parameters
    ----------
    analysis : what the report shows.
    clinician : True for the static and passive moments only (:data:`CLINICIAN_QUANTITIES`), False for every
        quantity with a budget (the engineer's appendix).
    """
    untared = {id(u.record) for u in analysis.untared}
    rows = []
    for arm in analysis.arms:
        latest = latest_usable(analysis, arm)
        if latest is None:
            continue
        record, name = latest
        for key in sorted(record.parameters, key=sort_key):
            if clinician and key[2] not in CLINICIAN_QUANTITIES:
                continue
            weight = key[0] == "segments" and key[2] in WEIGHT_QUANTITIES
            row = precision_of(record, name, key, left_out=UNTARED_LEFT_OUT if weight and id(record) in untared else "")
            if row is not None:
                rows.append(row)
    return rows
