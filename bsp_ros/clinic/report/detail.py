"""The detail pages as plain rows: what a clinician reads first, the arm against its peers, the engineer's appendix."""

from __future__ import annotations

import math
from dataclasses import dataclass

from bsp_ros.clinic.mdc import ErrorScale
from bsp_ros.clinic.report.analysis import NON_NEGATIVE, Analysis, Change, Series
from bsp_ros.clinic.report.labels import plain_name, plain_number, with_unit
from bsp_ros.clinic.report.priors import PRIOR_SOURCE, PeerRow
from bsp_ros.clinic.report.summary import arm_title, percent
from bsp_ros.clinic.store.curves import angle_of

PASSIVE = ("coulomb_nm", "stiffness_nm_per_rad", "viscous_nms")
"""The passive moments a clinician reads (the elastic offset and the curve's angles are in the appendix)."""
WEIGHT = ("static_moment_kgm", "mass_kg", "com_m")
"""The arm's weight and what is combined from it (the first moment repeats mass x centre of mass)."""
PEER_QUANTITIES = ("static_moment_kgm", "mass_kg")

PROTOCOL = (
    "The slow movements measure the passive, non-neural resistance of the relaxed arm at rest (joint friction, "
    "tissue stiffness and damping), not spasticity: they are too slow to provoke a stretch reflex."
)
APPENDIX_NOTE = (
    "Model internals: the elastic offsets, inertias, perpendicular moments and first moments, and the passive "
    "moment at each angle of the curve; changes in units only."
)
PEERS_NOTE = (
    f"Tables: {PRIOR_SOURCE} segment masses and centres of mass for the person's sex and body mass, the centres "
    "scaled to the measured segment lengths; the range is the population's ±2 SD (a z-score counts those SDs). "
    "The masses combine the measured weight with these tables, so they lean towards them; the static moments are "
    "measured alone."
)


def section(series: Series) -> str:
    """``passive``, ``weight``, ``length`` or ``appendix`` (inertia, perpendicular moments, model internals)."""
    group, _, quantity = series.key
    if quantity == "length_m":
        return "length"
    if group == "joints" and quantity in PASSIVE and angle_of(quantity) is None:
        return "passive"
    if group == "segments" and quantity in WEIGHT:
        return "weight"
    return "appendix"


@dataclass(frozen=True)
class DetailRow:
    """One parameter of one arm: the latest value, its changes and the limit they are judged by, as text."""

    name: str
    arm: str
    latest: str
    since_previous: str
    since_first: str
    error: str
    flagged: bool


def change_text(change: Change | None, unit: str, *, with_percent: bool = True) -> str:
    """``−0.2 N·m (−26 %)``; the % only where the earlier value is clear of 0; ``–`` without a change."""
    if change is None:
        return "–"
    sign = "+" if change.delta > 0 else "−"
    if plain_number(abs(change.delta)) == "0":
        return with_unit(0.0, unit)
    text = f"{sign}{with_unit(abs(change.delta), unit)}"
    if with_percent and change.percent is not None:
        text += f" ({sign}{percent(change.percent)})"
    return text


AT_ZERO_TEXT = "not judged (estimated at 0)"


def at_zero(series: Series) -> bool:
    """Whether the latest change of a judged ``series`` is not judged because a value sits at the bound 0 (the
    latest value, or the earlier one of every latest comparison): the data did not show the term."""
    latest = series.latest
    if not series.judged or latest is None or series.key[2] not in NON_NEGATIVE:
        return False
    changes = [c for c in (series.since_previous, series.since_first) if c is not None]
    return latest.value == 0.0 or (bool(changes) and all(c.at_bound for c in changes))


def mdc_text(series: Series) -> str:
    """The retest pairs' MDC95 of ``series`` in words: ``0.05 N·m``, or on the log scale its share of the value and
    that share of the latest value (``13 % (0.06 N·m at 0.45 N·m)``)."""
    error = series.error
    if error.scale is ErrorScale.ABSOLUTE or error.mdc95 is None:
        return with_unit(error.mdc95, series.unit)
    latest = series.latest
    value = latest.value if latest is not None else None
    share = percent(-100.0 * math.expm1(-error.mdc95))
    at = error.mdc95_at(value)
    if at is None or value is None:
        return share
    return f"{share} ({with_unit(at, series.unit)} at {with_unit(value, series.unit)})"


def error_text(series: Series) -> str:
    """The limit a change of ``series`` is flagged beyond, and the MDC95 it comes from, in words; ``not judged
    (estimated at 0)`` where a value at the bound 0 leaves the latest change unjudged."""
    error = series.error
    if at_zero(series):
        return AT_ZERO_TEXT
    if error.mdc95 is None:
        return "unknown (too few retests)" if series.judged else "not judged"
    whose = "this patient" if error.source == "subject" else "the cell"
    mdc = f"MDC95 {mdc_text(series)} from {error.n_pairs} retests of {whose}"
    if not series.judged:
        return f"{mdc}; for reference, not flagged"
    # The latest step's limit; where its earlier value is at the bound 0 (no ratio), the one since the first.
    limits = [c.limit for c in (series.since_previous, series.since_first) if c is not None and c.judged]
    limit = next((x for x in limits if x is not None), None)
    if limit is None:
        return mdc
    return f"flagged beyond {with_unit(limit, series.unit)}, when the next session confirms it ({mdc})"


def detail_rows(analysis: Analysis, wanted: str) -> list[DetailRow]:
    """The rows of one :func:`section` (``passive``, ``weight`` or ``appendix``), in display order."""
    rows = []
    for series in analysis.series:
        latest = series.latest
        if latest is None or section(series) != wanted:
            continue
        name = plain_name(series.key)
        near_zero = latest.value is not None and abs(latest.value) <= 2.0 * (latest.std or 0.0)
        rows.append(
            DetailRow(
                name[0].upper() + name[1:],
                (series.arm or "–").capitalize(),
                with_unit(latest.value, series.unit)
                + (f" ± {with_unit(latest.std, series.unit)}" if near_zero else ""),
                change_text(series.since_previous, series.unit, with_percent=wanted != "appendix"),
                change_text(series.since_first, series.unit, with_percent=wanted != "appendix"),
                error_text(series) if wanted != "appendix" else "",
                series.judged and (bool(series.changes) or series.possible is not None),
            )
        )
    return rows


def peer_rows(analysis: Analysis) -> list[tuple[str, PeerRow]]:
    """``(arm title, row)`` of each static moment and mass against its table prediction, from each arm's latest
    usable session with a table prediction."""
    rows = []
    for series in analysis.series:
        if series.key[0] != "segments" or series.key[2] not in PEER_QUANTITIES:
            continue
        point = next((p for p in reversed(series.points) if p.usable and p.prior is not None), None)
        if point is None or point.prior is None or point.value is None or not point.prior.std > 0:
            continue
        name = plain_name(series.key)
        row = PeerRow(series.key, name[0].upper() + name[1:], point.value, point.std or 0.0, point.prior, point.number)
        rows.append((arm_title(analysis, series.arm), row))
    return rows


def peer_cells(row: PeerRow, unit: str) -> tuple[str, str, str]:
    """``(measured, tables, against peers)`` as text: ``0.28 ± 0.08 kg·m``, ``0.21 (0.15 to 0.27) kg·m``,
    ``z +1.2: heavier than most``."""
    low, high = row.prior.mean - 2 * row.prior.std, row.prior.mean + 2 * row.prior.std
    tables = f"{with_unit(row.prior.mean, '')} ({with_unit(low, '')} to {with_unit(high, unit)})"
    z = f"z {'+' if row.z >= 0 else '−'}{abs(row.z):.1f}: {row.words}"
    return f"{with_unit(row.value, '')} ± {with_unit(row.std, unit)}", tables, z
