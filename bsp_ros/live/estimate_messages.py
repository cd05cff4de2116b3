"""The estimate as ROS message samples: DiagnosticArray, InertiaStamped, passive-moment JointState."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bsp_ros.core.estimate_schema import Estimate, Level
from msg_adapters.diagnostics import ERROR, OK, WARN, DiagnosticArraySample, DiagnosticStatusData
from msg_adapters.inertia import InertiaSample
from msg_adapters.joint_state import JointStateSample

LEVELS = {Level.OK: OK, Level.WEAK: WARN, Level.INVALID: ERROR}


def level_of(estimate: Estimate) -> int:
    """OK / WARN / ERROR for a valid / weak / invalid estimate."""
    return LEVELS[estimate.quality.level]


def diagnostics_from_estimate(estimate: Estimate, t_ns: int, prefix: str = "bsp") -> DiagnosticArraySample:
    """One status per segment and joint (every quantity's value, std and source) and one for quality.

    Keys are ``<quantity>``, ``<quantity>.std`` and ``<quantity>.source``, e.g. ``mass_kg.std``; a joint's passive
    curve adds ``passive_curve.<k>.angle_deg``, ``.moment_nm`` and ``.std_nm`` per point and
    ``passive_curve.stiffness_nm_per_rad`` (``.std``, ``.reference_angle_deg``).
    """
    level = level_of(estimate)
    quality = estimate.quality
    statuses = []
    for group in (estimate.segments, estimate.joints):
        for owner, quantities in group.items():
            values: dict[str, object] = {}
            for key, q in quantities.items():
                values[key] = q.value
                values[f"{key}.std"] = q.std
                values[f"{key}.source"] = str(q.source)
            if group is estimate.joints:
                values.update(_curve_values(estimate.passive_curves.get(owner)))
            statuses.append(DiagnosticStatusData.with_values(level, f"{prefix}/{owner}", quality.message, "", values))
    quality_values = {
        "valid": quality.valid,
        "n_samples": quality.n_samples,
        "condition_number": quality.condition_number,
        **{f"residual_rms_nm.{k}": v for k, v in quality.residual_rms_nm.items()},
        **{f"warning.{i}": w for i, w in enumerate(quality.warnings)},
    }
    statuses.append(DiagnosticStatusData.with_values(level, f"{prefix}/quality", quality.message, "", quality_values))
    return DiagnosticArraySample(t_ns, "", tuple(statuses))


def _curve_values(curve: Any) -> dict[str, object]:
    """A passive curve as diagnostic key/values (empty without one)."""
    if not isinstance(curve, dict):
        return {}
    values: dict[str, object] = {}
    for k, point in enumerate(zip(curve["angle_deg"], curve["moment_nm"], curve["std_nm"], strict=True)):
        for name, number in zip(("angle_deg", "moment_nm", "std_nm"), point, strict=True):
            values[f"passive_curve.{k}.{name}"] = number
    values["passive_curve.reference_angle_deg"] = curve.get("reference_angle_deg")
    values["passive_curve.stiffness_nm_per_rad"] = curve.get("stiffness_nm_per_rad")
    values["passive_curve.stiffness_nm_per_rad.std"] = curve.get("stiffness_std_nm_per_rad")
    return values


def inertias_from_estimate(estimate: Estimate, t_ns: int) -> dict[str, InertiaSample]:
    """Segment -> mass, COM and inertia in the segment's frame (x along the segment from its proximal joint,
    z the flexion axis, y completing it): the COM at ``[com_m, d, 0]`` with ``d`` the perpendicular moment over
    the mass, and ``izz`` the inertia about the COM for rotation in the movement plane; the out-of-plane
    components are not observable (0)."""
    out = {}
    for segment in estimate.segments:
        mass, com = _value(estimate, "mass_kg", segment), _value(estimate, "com_m", segment)
        if mass is None or com is None:
            continue
        normal = _value(estimate, "perpendicular_moment_kgm", segment)
        about_com = _value(estimate, "inertia_com_kgm2", segment)
        tensor = np.zeros((3, 3))
        tensor[2, 2] = max(float(about_com), 0.0) if about_com is not None else 0.0
        offset = float(normal) / float(mass) if normal is not None and mass > 0 else 0.0
        out[segment] = InertiaSample(t_ns, segment, float(mass), np.array([float(com), offset, 0.0]), tensor)
    return out


def _value(estimate: Estimate, key: str, owner: str) -> float | None:
    """The value of quantity ``key`` of ``owner``, or None where it has none."""
    q = estimate.quantity(key, owner)
    return None if q is None else q.value


def passive_moments_from_estimate(estimate: Estimate, t_ns: int) -> JointStateSample | None:
    """Joint names with effort = Coulomb amplitude (Nm); None when there is none.

    Where the estimate has passive curves, each curve point follows as ``<joint>/passive_curve/<k>`` with
    position = its angle (rad) and effort = the passive moment there (Nm); the Coulomb entries' position is NaN
    (no angle). The curves' std are on ``bsp/estimate`` (:func:`diagnostics_from_estimate`).
    """
    coulomb_nm = {joint: _value(estimate, "coulomb_nm", joint) for joint in estimate.joints}
    names = [joint for joint, value in coulomb_nm.items() if value is not None]
    if not names:
        return None
    effort = [float(value) for value in coulomb_nm.values() if value is not None]
    n_coulomb = len(names)
    position = [math.nan] * n_coulomb
    for joint in estimate.joints:
        curve = estimate.passive_curves.get(joint)
        if not isinstance(curve, dict):
            continue
        for k, (angle_deg, moment_nm) in enumerate(zip(curve["angle_deg"], curve["moment_nm"], strict=True)):
            names.append(f"{joint}/passive_curve/{k}")
            position.append(math.radians(angle_deg))
            effort.append(float(moment_nm))
    if len(names) == n_coulomb:
        position = []  # no curve: the message as before (effort only)
    return JointStateSample(t_ns, "", tuple(names), np.array(position), np.zeros(0), np.array(effort))
