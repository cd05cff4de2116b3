"""Which trends go where: the passive moments on the first page, the rest in the detail (never lengths)."""

from __future__ import annotations

from bsp_ros.clinic.report.analysis import Analysis, Series, is_passive
from bsp_ros.clinic.report.labels import sort_key
from bsp_ros.clinic.report.plots import Panel
from bsp_ros.clinic.report.summary import arm_title
from bsp_ros.clinic.store.records import ParamKey

FIRST_PAGE_PANELS = 6
NOT_PLOTTED = ("length_m", "first_moment_kgm")
"""Lengths are geometry from the markers (in the detail table), the first moment repeats mass x COM."""


def _panels(analysis: Analysis, keys: list[ParamKey]) -> list[Panel]:
    by_key: dict[ParamKey, list[Series]] = {}
    for series in analysis.series:
        by_key.setdefault(series.key, []).append(series)
    return [by_key[k] for k in keys if k in by_key]


def _measured(series: list[Series]) -> bool:
    """Some arm has a usable value that is not at the bound 0 (a passive term the data never supported)."""
    return any(p.usable and p.value != 0.0 for s in series for p in s.points)


def _determined(series: list[Series]) -> bool:
    """The data determine the parameter: its typical ±2 SD is less than its typical size (else: detail only)."""
    import statistics

    usable = [p for s in series for p in s.points if p.usable and p.value is not None]
    if not usable:
        return False
    size = statistics.median(abs(p.value or 0.0) for p in usable)
    spread = statistics.median(2 * (p.std or 0.0) for p in usable)
    return spread < size


def arm_names(analysis: Analysis) -> list[str]:
    """Legend names of the arms, in series order."""
    return [arm_title(analysis, arm) for arm in analysis.arms]


def first_page_panels(analysis: Analysis) -> list[Panel]:
    """Passive-moment trends: changed ones first, then by joint, at most :data:`FIRST_PAGE_PANELS`."""
    keys = sorted({s.key for s in analysis.series if is_passive(s.key)}, key=sort_key)
    panels = [p for p in _panels(analysis, keys) if _measured(list(p)) and _determined(list(p))]
    flagged = [p for p in panels if any(s.changes for s in p)]
    chosen = flagged + [p for p in panels if p not in flagged]
    chosen = chosen[:FIRST_PAGE_PANELS]
    return sorted(chosen, key=lambda p: sort_key(p[0].key))


def _groups(analysis: Analysis) -> list[tuple[str, list[Panel]]]:
    shown = {p[0].key for p in first_page_panels(analysis)}
    keys = sorted({s.key for s in analysis.series}, key=sort_key)
    rest = [k for k in keys if k not in shown and k[2] not in NOT_PLOTTED]
    groups = [
        ("Arm weight (static moments)", [k for k in rest if k[2] == "static_moment_kgm"]),
        (
            "Masses and centres of mass (measured weight combined with tables)",
            [k for k in rest if k[2] in ("mass_kg", "com_m")],
        ),
        (APPENDIX_GROUP, [k for k in rest if k[0] == "joints"]),
    ]
    found = []
    for title, chosen in groups:
        panels = [p for p in _panels(analysis, chosen) if _measured(list(p))]
        if panels:
            found.append((title, panels))
    return found


APPENDIX_GROUP = "Further passive-moment terms"


def detail_groups(analysis: Analysis) -> list[tuple[str, list[Panel]]]:
    """Titled groups of the remaining trends a clinician reads: the arm weight, masses and centres of mass."""
    return [g for g in _groups(analysis) if g[0] != APPENDIX_GROUP]


def appendix_groups(analysis: Analysis) -> list[tuple[str, list[Panel]]]:
    """The engineer's trends: passive-moment terms not on the first page (elastic offsets, curve angles)."""
    return [g for g in _groups(analysis) if g[0] == APPENDIX_GROUP]
