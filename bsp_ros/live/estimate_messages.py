"""The estimate document as ROS message samples: DiagnosticArray, InertiaStamped, passive-moment JointState."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bsp_ros.core.quantities import PASSIVE_CURVE, is_quantity, passive_curves_of
from msg_adapters.diagnostics import ERROR, OK, WARN, DiagnosticArraySample, DiagnosticStatusData
from msg_adapters.inertia import InertiaSample
from msg_adapters.joint_state import JointStateSample

LEVELS = {"ok": OK, "weak": WARN, "invalid": ERROR}


def level_of(document: dict[str, Any]) -> int:
    """OK / WARN / ERROR for a valid / weak / invalid estimate."""
    return LEVELS.get(document["quality"].get("level", "invalid"), ERROR)


def diagnostics_from_estimate(document: dict[str, Any], t_ns: int, prefix: str = "bsp") -> DiagnosticArraySample:
    """One status per segment and joint (every quantity's value, std and source) and one for quality.

    Keys are ``<quantity>``, ``<quantity>.std`` and ``<quantity>.source``, e.g. ``mass_kg.std``; a joint's passive
    curve adds ``passive_curve.<k>.angle_deg``, ``.moment_nm`` and ``.std_nm`` per point and
    ``passive_curve.stiffness_nm_per_rad`` (``.std``, ``.reference_angle_deg``).
    """
    level = level_of(document)
    quality = document["quality"]
    statuses = []
    for group in ("segments", "joints"):
        for owner, quantities in document.get(group, {}).items():
            values: dict[str, object] = {}
            for key, q in quantities.items():
                if is_quantity(q):
                    values[key] = q["value"]
                    values[f"{key}.std"] = q["std"]
                    values[f"{key}.source"] = q["source"]
            values.update(_curve_values(quantities.get(PASSIVE_CURVE)))
            statuses.append(
                DiagnosticStatusData.with_values(level, f"{prefix}/{owner}", quality.get("message", ""), "", values)
            )
    quality_values = {
        "valid": quality["valid"],
        "n_samples": quality["n_samples"],
        "condition_number": quality["condition_number"],
        **{f"residual_rms_nm.{k}": v for k, v in quality.get("residual_rms_nm", {}).items()},
        **{f"warning.{i}": w for i, w in enumerate(quality.get("warnings", []))},
    }
    statuses.append(
        DiagnosticStatusData.with_values(level, f"{prefix}/quality", quality.get("message", ""), "", quality_values)
    )
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


def inertias_from_estimate(document: dict[str, Any], t_ns: int) -> dict[str, InertiaSample]:
    """Segment -> mass, COM and inertia in the segment's frame (x along the segment from its proximal joint,
    z the flexion axis, y completing it): the COM at ``[com_m, d, 0]`` with ``d`` the perpendicular moment over
    the mass, and ``izz`` the inertia about the COM for rotation in the movement plane; the out-of-plane
    components are not observable (0)."""
    out = {}
    for segment, quantities in document.get("segments", {}).items():
        mass, com = quantities.get("mass_kg", {}).get("value"), quantities.get("com_m", {}).get("value")
        if mass is None or com is None:
            continue
        normal = quantities.get("perpendicular_moment_kgm", {}).get("value")
        about_com = quantities.get("inertia_com_kgm2", {}).get("value")
        tensor = np.zeros((3, 3))
        tensor[2, 2] = max(float(about_com), 0.0) if about_com is not None else 0.0
        offset = float(normal) / float(mass) if normal is not None and mass > 0 else 0.0
        out[segment] = InertiaSample(t_ns, segment, float(mass), np.array([float(com), offset, 0.0]), tensor)
    return out


def passive_moments_from_estimate(document: dict[str, Any], t_ns: int) -> JointStateSample | None:
    """Joint names with effort = Coulomb amplitude (Nm); None when there is none.

    Where the estimate has passive curves, each curve point follows as ``<joint>/passive_curve/<k>`` with
    position = its angle (rad) and effort = the passive moment there (Nm); the Coulomb entries' position is NaN
    (no angle). The curves' std are on ``bsp/estimate`` (:func:`diagnostics_from_estimate`).
    """
    joints = document.get("joints", {})
    names = [j for j, q in joints.items() if q.get("coulomb_nm", {}).get("value") is not None]
    if not names:
        return None
    effort = [float(joints[j]["coulomb_nm"]["value"]) for j in names]
    n_coulomb = len(names)
    position = [math.nan] * n_coulomb
    for joint, curve in passive_curves_of(document):
        for k, (angle_deg, moment_nm) in enumerate(zip(curve["angle_deg"], curve["moment_nm"], strict=True)):
            names.append(f"{joint}/passive_curve/{k}")
            position.append(math.radians(angle_deg))
            effort.append(float(moment_nm))
    if len(names) == n_coulomb:
        position = []  # no curve: the message as before (effort only)
    return JointStateSample(t_ns, "", tuple(names), np.array(position), np.zeros(0), np.array(effort))
