"""The covariance ledger: an estimate's covariance as a sum of named terms, its uncertainty budget.

Each source of uncertainty the estimator accounts for adds its own (p, p) covariance term: the fit's sensor noise,
the marker placement, the choice of passive model, the friction's shape, a drifting sensor's level, the sensor's
zero. Their sum is the estimate's covariance, and the diagonal of each term is its share of each parameter's
variance (ISO GUM's uncertainty budget: the standard uncertainty is the root of the sum of the contributions'
squares). Terms are independent by construction: each is the effect of one source on the estimate.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

__all__ = ["Ledger", "Term"]


class Term(StrEnum):
    """A named source of uncertainty (the keys of the estimate JSON's ``budget``)."""

    SENSOR_NOISE = "sensor_noise"
    """The fit's own (HAC) covariance: the sensor's noise and errors correlated along the stream, with the prior
    where the data leave a parameter to it. Shrinks with a longer session."""
    MARKER_PLACEMENT = "marker_placement"
    """Skin markers off their joint centres and the contact point off its assumed place (1 sd per axis):
    firmer markers on their landmarks, or the robot's handle pose for the contact point, shrink it."""
    MODEL_CHOICE = "model_choice"
    """The passive models the data cannot choose between, or a fixed nonlinear model's assumed shape: wider or
    independent joint motion (bsp plan) shrinks it."""
    FRICTION_SHAPE = "friction_shape"
    """Whether friction steps or changes smoothly at low speed, and which law holds there (Coulomb amplitudes
    only): a protocol that leaves the friction transition more often shrinks it."""
    DRIFT = "drift"
    """A drifting force sensor's unknown level: a warmed-up, re-tared sensor removes it."""
    SENSOR_ZERO = "sensor_zero"
    """The force sensor's zero: a tare's own uncertainty, or without one the assumed zero; a tare shrinks it."""
    CONTACT_SLIP = "contact_slip"
    """A hand that slipped in the handle: how far the parameters move between the coarsest and the finest
    estimate of the contact point's travel, and between counting it from the session's start and from its mean.
    A strap that keeps the hand against the handle's stop removes it."""
    STATIC_MOMENT_BOUND = "static_moment_bound"
    """A static moment the data put below 0, held at its bound: how far holding it there moves the other
    parameters (rank one). A longer session or a protocol that moves that segment more shrinks it."""
    WINDOW_CHECK = "window_check"
    """The recursive mode: its window's checked variances and the filter's distance from that window's values."""

    @property
    def remedy(self) -> str:
        """What would shrink this term, in one phrase."""
        return _REMEDIES[self.value]


_REMEDIES = {
    "sensor_noise": "a longer session or more motion shrinks it",
    "marker_placement": "markers firmly on their landmarks shrink it (--marker-placement-sd-mm says how firm)",
    "model_choice": "wider, independent joint motion shrinks it (bsp plan)",
    "friction_shape": "a protocol that leaves the friction transition more often shrinks it",
    "drift": "a warmed-up, re-tared sensor removes it",
    "sensor_zero": "a tare shrinks it (bsp tare, then --tare FILE)",
    "contact_slip": "a strap that keeps the hand against the handle's stop removes it",
    "static_moment_bound": "a longer session, or more motion of the segment held at 0, shrinks it",
    "window_check": "a longer window shrinks it",
}


@dataclass(frozen=True)
class Ledger:
    """Named covariance terms, each (p, p), in the order they were added.

    Attributes
    ----------
    terms : (term, covariance) pairs; a term appears at most once.
    """

    terms: tuple[tuple[Term, np.ndarray], ...] = ()

    @classmethod
    def of(cls, term: Term, covariance: np.ndarray) -> Ledger:
        """A ledger of one term."""
        return cls(((term, covariance),))

    def __iter__(self) -> Iterator[tuple[Term, np.ndarray]]:
        return iter(self.terms)

    def __contains__(self, term: object) -> bool:
        return any(name == term for name, _ in self.terms)

    def get(self, term: Term) -> np.ndarray | None:
        """The covariance of ``term``, or None where it has none."""
        return next((covariance for name, covariance in self.terms if name == term), None)

    def plus(self, term: Term, covariance: np.ndarray) -> Ledger:
        """This ledger with ``covariance`` added to ``term`` (a new term at the end where it has none)."""
        if term not in self:
            return Ledger((*self.terms, (term, covariance)))
        return Ledger(tuple((name, c + covariance if name == term else c) for name, c in self.terms))

    def with_term(self, term: Term, covariance: np.ndarray) -> Ledger:
        """This ledger with ``term``'s covariance replaced by ``covariance`` (added at the end where it has none)."""
        if term not in self:
            return Ledger((*self.terms, (term, covariance)))
        return Ledger(tuple((name, covariance if name == term else c) for name, c in self.terms))

    def without(self, *terms: Term) -> Ledger:
        """This ledger without ``terms``."""
        return Ledger(tuple((name, c) for name, c in self.terms if name not in terms))

    def joined(self, other: Ledger) -> Ledger:
        """The terms of both (those of ``other`` added to this one's of the same name)."""
        out = self
        for term, covariance in other:
            out = out.plus(term, covariance)
        return out

    def total(self, size: int) -> np.ndarray:
        """(size, size) the sum of the terms: the estimate's covariance (zeros without terms)."""
        out = np.zeros((size, size))
        for _, covariance in self.terms:
            out = out + covariance
        return out

    def contributions(self, index: int) -> dict[str, float]:
        """Each term's standard uncertainty of parameter ``index``: the root of its variance share (the total's
        variance is the sum of their squares)."""
        return {str(term): float(np.sqrt(max(float(c[index, index]), 0.0))) for term, c in self.terms}
