"""Published healthy ranges of passive joint moments, and where an estimate sits against one.

Only ranges whose quantity and unit are what bsp_ros measures are listed (docs/clinic.md, "References for the
healthy ranges", names the sources found and why the others are not compared). A range is an orientation for the
clinician, not a diagnosis: the published conditions (method, angles, speed) differ from the slow robot protocol.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum


class RangeKind(StrEnum):
    """What a range's two ends are."""

    OBSERVED = "observed"
    """The lowest and the highest value among the healthy people measured."""
    MEAN_2SD = "mean_2sd"
    """The healthy mean ± 2 SD."""


@dataclass(frozen=True, kw_only=True)
class HealthyRange:
    """A published range of one passive quantity of one joint in healthy adults.

    Attributes
    ----------
    joint : ``shoulder``, ``elbow`` or ``wrist``.
    quantity : the estimate's quantity key (``stiffness_nm_per_rad``, ``coulomb_nm``, ...).
    unit : the unit of ``low`` and ``high``, as bsp_ros reports the quantity.
    low, high : the range's ends, in ``unit``.
    kind : what the ends are (the observed extremes, or mean ± 2 SD).
    population : who was measured, in words.
    n_subjects : how many.
    conditions : how, in words (method, posture, what differs from the slow robot protocol).
    citation : short form for the report (``Wiegner and Watts (1986)``).
    reference : the full reference.
    url : where the retrieved text was read.
    """

    joint: str
    quantity: str
    unit: str
    low: float
    high: float
    kind: RangeKind
    population: str
    n_subjects: int
    conditions: str
    citation: str
    reference: str
    url: str


HEALTHY_RANGES: tuple[HealthyRange, ...] = (
    HealthyRange(
        joint="elbow",
        quantity="stiffness_nm_per_rad",
        unit="N·m/rad",
        low=0.40,
        high=1.8,
        kind=RangeKind.OBSERVED,
        population="healthy adults (normal controls), relaxed arm",
        n_subjects=19,
        conditions=(
            "passive elastic stiffness of the relaxed elbow from the displacements a torque motor produced at the "
            "joint; it grew with upper-arm volume (r = 0.85), so a large arm sits higher in the range"
        ),
        citation="Wiegner and Watts (1986)",
        reference=(
            "Wiegner AW, Watts RL. Elastic properties of muscles measured at the elbow in man: I. Normal controls. "
            "Journal of Neurology, Neurosurgery, and Psychiatry 1986; 49(10): 1171-1176."
        ),
        url="http://jnnp.bmj.com/content/49/10/1171",
    ),
)


def healthy_range(joint: str, quantity: str) -> HealthyRange | None:
    """The published healthy range of ``quantity`` at ``joint``, or None where none was found."""
    return next((r for r in HEALTHY_RANGES if r.joint == joint and r.quantity == quantity), None)


class Placement(StrEnum):
    """Where an estimate (value ± 2 SD) sits against a healthy range."""

    WITHIN = "within"
    """The whole ±2 SD interval lies within the range."""
    ABOVE = "above"
    """The value minus 2 SD is above the high end."""
    BELOW = "below"
    """The value plus 2 SD is below the low end."""
    NEAR_HIGH = "near_high"
    """The value's ±2 SD interval reaches past the high end only: not distinguishable from it."""
    NEAR_LOW = "near_low"
    """The value's ±2 SD interval reaches past the low end only."""
    TOO_ROUGH = "too_rough"
    """The ±2 SD interval reaches past both ends (or the SD is unknown): the estimate cannot be placed."""
    AT_BOUND = "at_bound"
    """The estimate sits at its bound 0: the movement did not show the term, so it is not placed."""
    NO_RANGE = "no_range"
    """No published healthy range was found for this quantity and joint."""


PLACEMENT_WORDS = {
    Placement.WITHIN: "within the healthy range",
    Placement.ABOVE: "above the healthy range",
    Placement.BELOW: "below the healthy range",
    Placement.NEAR_HIGH: "at the high end of the healthy range (within 2 SD of it)",
    Placement.NEAR_LOW: "at the low end of the healthy range (within 2 SD of it)",
    Placement.TOO_ROUGH: "measured too roughly to place against the healthy range",
    Placement.AT_BOUND: "not shown by the movement (estimated at 0)",
    Placement.NO_RANGE: "no published range",
}
"""Each placement in the words of the report."""


def place(value: float, std: float | None, healthy: HealthyRange | None) -> Placement:
    """Where ``value`` (± 2 ``std``) sits against ``healthy``.

    Parameters
    ----------
    value : the estimate, in the range's unit.
    std : its standard deviation, same unit (None or not finite: the estimate cannot be placed).
    healthy : the range, None where none is published.

    Returns
    -------
    Placement
        ``ABOVE`` only when ``value - 2 std`` is above ``high``, ``BELOW`` only when ``value + 2 std`` is below
        ``low``, ``WITHIN`` when ``value ± 2 std`` lies inside ``[low, high]``; otherwise ``NEAR_HIGH`` or
        ``NEAR_LOW`` (the interval reaches past one end) or ``TOO_ROUGH`` (past both, or no usable std).
    """
    if healthy is None:
        return Placement.NO_RANGE
    if std is None or not math.isfinite(value) or not math.isfinite(std) or std < 0.0:
        return Placement.TOO_ROUGH
    lowest, highest = value - 2.0 * std, value + 2.0 * std
    if lowest > healthy.high:
        return Placement.ABOVE
    if highest < healthy.low:
        return Placement.BELOW
    past_low, past_high = lowest < healthy.low, highest > healthy.high
    if past_low and past_high:
        return Placement.TOO_ROUGH
    if past_high:
        return Placement.NEAR_HIGH
    if past_low:
        return Placement.NEAR_LOW
    return Placement.WITHIN
