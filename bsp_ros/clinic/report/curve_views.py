"""Torque-angle curves a clinician compares: per arm and joint, the first and the latest usable session's curve."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bsp_ros.clinic.report.analysis import Analysis
from bsp_ros.clinic.store.curves import angle_of
from bsp_ros.clinic.store.records import SessionRecord

JOINT_ORDER = ("shoulder", "elbow", "wrist")
CURVES_TITLE = "Passive moment against joint angle: first and latest session"
CURVES_CAPTION = (
    "Over the range each session measured: dashed grey, the first usable session; solid, the latest; shaded, "
    "±2 SD; red circles, angles where the moment changed by more than the measurement error. Sessions that could "
    "not be used are left out."
)


@dataclass(frozen=True)
class CurveSession:
    """One session's passive curve: its number in the report (retests not counted), its start, and the curve."""

    number: int
    time_ns: int
    angle_deg: tuple[float, ...]
    moment_nm: tuple[float, ...]
    std_nm: tuple[float, ...]


@dataclass(frozen=True)
class CurveView:
    """One joint of one arm: the first and (if another) the latest usable session's torque-angle curve.

    ``changed_deg`` are the angles whose passive moment differs between the two beyond the day-to-day
    measurement error (the same judgement as the trend of that angle: :class:`~.analysis.Change`).
    """

    arm: str | None
    joint: str
    first: CurveSession
    latest: CurveSession | None
    changed_deg: tuple[int, ...]


def _curve_session(analysis: Analysis, record: SessionRecord, curve: dict[str, Any]) -> CurveSession:
    return CurveSession(
        number=int(analysis.label_of(record)),
        time_ns=record.session_time_ns,
        angle_deg=tuple(curve["angle_deg"]),
        moment_nm=tuple(curve["moment_nm"]),
        std_nm=tuple(curve.get("std_nm") or [0.0] * len(curve["angle_deg"])),
    )


def _changed_angles(analysis: Analysis, arm: str | None, joint: str, first: int, latest: int) -> tuple[int, ...]:
    """Angles with a flagged change (a step confirmed by the next session) between sessions ``first`` and
    ``latest`` (numbers)."""
    found = []
    for series in analysis.arm_series(arm):
        group, part, quantity = series.key
        angle = angle_of(quantity)
        if group != "joints" or part != joint or angle is None or not series.judged:
            continue
        if any(first <= c.before.number and c.after.number <= latest for c in series.changes):
            found.append(angle)
    return tuple(sorted(set(found)))


def curve_views(analysis: Analysis) -> list[CurveView]:
    """Per arm (the analysis's order) and joint (proximal first), the curves to draw; none without a curve.

    Only valid sessions count (an invalid session's curve is never drawn), retests are left out; the first is
    the earliest such session with a curve of that joint, the latest the most recent one.
    """
    views = []
    for arm in analysis.arms:
        visits = [r for r in analysis.visits(arm) if r.quality.valid and r.passive_curves]
        joints = sorted(
            {j for r in visits for j in r.passive_curves},
            key=lambda j: (JOINT_ORDER.index(j) if j in JOINT_ORDER else len(JOINT_ORDER), j),
        )
        for joint in joints:
            having = [r for r in visits if joint in r.passive_curves and len(r.passive_curves[joint]["angle_deg"]) > 1]
            if not having:
                continue
            first = _curve_session(analysis, having[0], having[0].passive_curves[joint])
            latest = _curve_session(analysis, having[-1], having[-1].passive_curves[joint]) if len(having) > 1 else None
            changed = _changed_angles(analysis, arm, joint, first.number, latest.number) if latest else ()
            views.append(CurveView(arm, joint, first, latest, changed))
    return views
