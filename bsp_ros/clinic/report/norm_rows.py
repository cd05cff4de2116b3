"""The passive moments of each arm's latest usable session against published healthy ranges, as report rows."""

from __future__ import annotations

from dataclasses import dataclass

from bsp_ros.clinic.report.analysis import NON_NEGATIVE, Analysis
from bsp_ros.clinic.report.labels import plain_name, with_unit
from bsp_ros.clinic.report.norms import PLACEMENT_WORDS, HealthyRange, Placement, RangeKind, healthy_range, place
from bsp_ros.clinic.report.summary import arm_title, short_name
from bsp_ros.clinic.store.curves import angle_of

NORM_QUANTITIES = ("coulomb_nm", "stiffness_nm_per_rad", "viscous_nms")
"""The passive quantities a published range could be held against (those the detail shows)."""
NORMS_TITLE = "Passive moments against healthy ranges"
NORMS_NOTE = (
    "A value is above or below a healthy range only when it stays outside it by more than 2 SD of its own "
    "uncertainty. The published ranges were measured with other methods, angles and speeds than this slow "
    "protocol: they orient, they do not diagnose."
)


@dataclass(frozen=True, kw_only=True)
class NormRow:
    """One passive quantity of one arm's latest usable session against its published healthy range."""

    arm: str
    label: str
    value: float
    std: float
    session: int
    healthy: HealthyRange
    placement: Placement

    @property
    def measured(self) -> str:
        """``1.3 ± 0.2 N·m/rad``."""
        return f"{with_unit(self.value, '')} ± {with_unit(self.std, self.healthy.unit)}"

    @property
    def range_text(self) -> str:
        """``0.4 to 1.8 N·m/rad (19 healthy adults, lowest to highest)``."""
        what = "lowest to highest" if self.healthy.kind is RangeKind.OBSERVED else "mean ± 2 SD"
        ends = f"{with_unit(self.healthy.low, '')} to {with_unit(self.healthy.high, self.healthy.unit)}"
        return f"{ends} ({self.healthy.n_subjects} healthy adults, {what})"

    @property
    def words(self) -> str:
        """The placement in words (``within the healthy range``)."""
        return PLACEMENT_WORDS[self.placement]


def norm_rows(analysis: Analysis) -> tuple[list[NormRow], list[str]]:
    """The rows of the passive quantities with a published healthy range, and the names of those without one.

    Each row is the latest usable session of one arm; a value at the bound 0 of a non-negative term is shown as
    not shown by the movement rather than placed below the range.
    """
    rows, without = [], []
    for series in analysis.series:
        group, joint, quantity = series.key
        latest = series.latest
        if group != "joints" or quantity not in NORM_QUANTITIES or angle_of(quantity) is not None:
            continue
        if latest is None or latest.value is None:
            continue
        healthy = healthy_range(joint, quantity)
        if healthy is None:
            if short_name(series.key) not in without:
                without.append(short_name(series.key))
            continue
        name = plain_name(series.key)
        at_bound = quantity in NON_NEGATIVE and latest.value == 0.0
        rows.append(
            NormRow(
                arm=arm_title(analysis, series.arm),
                label=name[0].upper() + name[1:],
                value=latest.value,
                std=latest.std if latest.std is not None else float("nan"),
                session=latest.number,
                healthy=healthy,
                placement=Placement.AT_BOUND if at_bound else place(latest.value, latest.std, healthy),
            )
        )
    return rows, without


def sources_text(rows: list[NormRow]) -> str:
    """Each range shown, once: its citation, who and how it was measured, and the full reference."""
    shown: list[HealthyRange] = []
    for row in rows:
        if row.healthy not in shown:
            shown.append(row.healthy)
    return " ".join(f"{r.citation}: {r.n_subjects} {r.population}; {r.conditions}. {r.reference}" for r in shown)


def without_text(without: list[str]) -> str:
    """``No published healthy range was found for: shoulder friction, elbow friction.`` (empty without any)."""
    return f"No published healthy range was found for: {', '.join(without)}." if without else ""
