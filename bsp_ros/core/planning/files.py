"""Planned protocols as files: JSON (schema ``bsp_ros/plan/1``) and CSV, and loading them back."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import numpy as np

from bsp_ros.core.planning.planner import Plan
from bsp_ros.core.planning.safety import JointLimits, check_reachable, check_trajectory_within
from bsp_ros.core.planning.trajectory import PlannedTrajectory, handle_poses_world
from bsp_ros.core.streams import joints_for, segments_for
from bsp_ros.errors import InputError

PLAN_SCHEMA = "bsp_ros/plan/1"
#: Default sample rate of the files' dense samples, Hz.
SAMPLE_HZ = 10.0


def sampled_path(plan: Plan, rate_hz: float = SAMPLE_HZ) -> dict[str, np.ndarray]:
    """The path on a uniform grid: ``t_s`` (N,), ``q_rad`` (N, n), ``qdot_rad_s`` (N, n), ``handle`` (N, 3)."""
    t = plan.trajectory.sample_times_s(rate_hz)
    q = plan.trajectory.angles_rad(t)
    return {
        "t_s": t,
        "q_rad": q,
        "qdot_rad_s": plan.trajectory.velocities_rad_s(t),
        "handle": handle_poses_world(q, plan.request.nominal.lengths_m, plan.request.shoulder_yz_m),
    }


def plan_to_dict(plan: Plan, rate_hz: float = SAMPLE_HZ) -> dict[str, Any]:
    """JSON-ready dict (schema ``bsp_ros/plan/1``): inputs, knots, dense samples, predicted stds.

    Returns
    -------
    dict with ``schema``, ``joints``, ``segments``, ``lengths_m``, ``shoulder_yz_m``, ``limits``
    (``{joint: {low_deg, high_deg}}``, ``max_speed_rad_s``), ``duration_s``, ``passive_model``,
    ``operating_points_deg``, ``amplitudes_deg``, ``knots`` (``t_s``, ``q_rad``, ``qdot_rad_s``: the exact
    trajectory), ``samples`` (``t_s``, ``q_rad``, ``qdot_rad_s``, ``handle_y_m``, ``handle_z_m``,
    ``handle_pitch_rad`` in ``world``), ``predicted`` (one row per parameter: the std `bsp identify` will report,
    its ``budget`` {term: standard uncertainty} and ``largest_term``), ``uncertainty`` (what the std assumes of
    the session: marker placement, contact point, tare or sensor zero), ``inertia_ratio``, ``notes``; with
    ``--passive auto`` also ``passive_choice`` (``chosen``, ``open_models``, ``check_valid``: the model `bsp
    identify` chose on the nominal arm, whose std ``predicted`` is, and the models its data left open).
    """
    request = plan.request
    n = request.nominal.n_joints
    joints = joints_for(n)
    t, q, qdot = plan.trajectory.knots
    path = sampled_path(plan, rate_hz)
    return {
        "schema": PLAN_SCHEMA,
        "joints": list(joints),
        "segments": list(segments_for(n)),
        "lengths_m": list(request.nominal.lengths_m),
        "shoulder_yz_m": list(request.shoulder_yz_m),
        "limits": {
            "range_deg": {
                joint: {"low_deg": lo, "high_deg": hi}
                for joint, (lo, hi) in zip(joints, request.limits.range_deg, strict=True)
            },
            "max_speed_rad_s": request.limits.max_speed_rad_s,
        },
        "duration_s": plan.trajectory.duration_s,
        "passive_model": request.passive.label,
        "operating_points_deg": plan.centres_deg.tolist(),
        "amplitudes_deg": plan.amplitudes_deg.tolist(),
        "peak_speed_rad_s": dict(zip(joints, plan.trajectory.peak_speed_rad_s, strict=True)),
        "knots": {"t_s": t.tolist(), "q_rad": q.tolist(), "qdot_rad_s": qdot.tolist()},
        "samples": {
            "rate_hz": rate_hz,
            "t_s": path["t_s"].tolist(),
            "q_rad": path["q_rad"].tolist(),
            "qdot_rad_s": path["qdot_rad_s"].tolist(),
            "handle_y_m": path["handle"][:, 0].tolist(),
            "handle_z_m": path["handle"][:, 1].tolist(),
            "handle_pitch_rad": path["handle"][:, 2].tolist(),
        },
        "predicted": plan.reported.table(),
        "uncertainty": request.session.to_dict(request.noise),
        "noise": {
            "force_noise_n": request.noise.force_noise_n,
            "torque_noise_nm": request.noise.torque_noise_nm,
            "marker_noise_m": request.noise.marker_noise_m,
            "wrench_hz": request.noise.wrench_hz,
            "marker_hz": request.noise.marker_hz,
        },
        "condition_number": plan.prediction.condition_number,
        "inertia_ratio": dict(zip(joints, (float(r) for r in plan.inertia_ratio), strict=True)),
        "notes": list(plan.notes),
        **({} if plan.auto_choice is None else {"passive_choice": plan.auto_choice.to_dict()}),
    }


def csv_columns(n_joints: int) -> list[str]:
    """Column names of the plan CSV."""
    joints = joints_for(n_joints)
    return (
        ["t_s"]
        + [f"{j}_rad" for j in joints]
        + [f"{j}_rad_s" for j in joints]
        + ["handle_y_m", "handle_z_m", "handle_pitch_rad"]
    )


def write_plan_json(path: Path, plan: Plan, rate_hz: float = SAMPLE_HZ) -> Path:
    """Write :func:`plan_to_dict` as JSON; return the path."""
    path = Path(path)
    path.write_text(json.dumps(plan_to_dict(plan, rate_hz), indent=1) + "\n", encoding="utf-8")
    return path


def write_plan_csv(path: Path, plan: Plan, rate_hz: float = SAMPLE_HZ) -> Path:
    """Write the dense samples (time, joint angles and velocities, handle pose in ``world``) as CSV."""
    path = Path(path)
    samples = sampled_path(plan, rate_hz)
    table = np.column_stack((samples["t_s"], samples["q_rad"], samples["qdot_rad_s"], samples["handle"]))
    with path.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.writer(handle)
        writer.writerow(csv_columns(plan.request.nominal.n_joints))
        writer.writerows([[repr(float(v)) for v in row] for row in table])
    return path


def _from_json(data: Any, where: str) -> PlannedTrajectory:
    if not isinstance(data, dict) or data.get("schema") != PLAN_SCHEMA:
        found = data.get("schema") if isinstance(data, dict) else type(data).__name__
        raise InputError(f"{where}: not a {PLAN_SCHEMA} file (schema {found!r})")
    try:
        knots = data["knots"]
        trajectory = PlannedTrajectory(knots["t_s"], knots["q_rad"], knots["qdot_rad_s"])
        joints = joints_for(trajectory.n_joints)
        ranges = tuple(
            (data["limits"]["range_deg"][j]["low_deg"], data["limits"]["range_deg"][j]["high_deg"]) for j in joints
        )
        limits = JointLimits(ranges, data["limits"]["max_speed_rad_s"])
        lengths, shoulder = data["lengths_m"], data["shoulder_yz_m"]
    except (KeyError, TypeError) as error:
        raise InputError(f"{where}: missing or malformed plan field {error}") from None
    check_trajectory_within(trajectory, limits)
    check_reachable(trajectory, lengths, shoulder)
    return trajectory


def _from_csv(path: Path) -> PlannedTrajectory:
    with path.open(newline="", encoding="utf-8") as handle:
        rows = list(csv.reader(handle))
    if not rows:
        raise InputError(f"{path}: empty CSV")
    header = rows[0]
    n = 3 if len(header) == len(csv_columns(3)) else 2
    if header != csv_columns(n):
        raise InputError(f"{path}: CSV columns must be {csv_columns(3)} (or the 2-joint set), got {header}")
    try:
        table = np.array([[float(v) for v in row] for row in rows[1:]], dtype=np.float64)
    except ValueError as error:
        raise InputError(f"{path}: a CSV value is not a number ({error})") from None
    if table.ndim != 2 or table.shape[0] < 2:
        raise InputError(f"{path}: a plan CSV needs at least 2 rows of samples")
    return PlannedTrajectory(table[:, 0], table[:, 1 : 1 + n], table[:, 1 + n : 1 + 2 * n])


def planned_trajectory_from_file(path: str | Path) -> PlannedTrajectory:
    """Load a planned trajectory that ``bsp plan`` wrote (JSON or CSV), e.g. for ``cell_simulator``.

    A JSON plan is the exact trajectory and is checked again against its own limits and for reachability;
    a CSV is interpolated (cubic Hermite) through its samples with their velocities.

    Raises
    ------
    InputError
        A missing, foreign or malformed file, or a trajectory that leaves its limits.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"plan file {str(path)!r} does not exist")
    if path.suffix.lower() == ".csv":
        return _from_csv(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise InputError(f"{path}: not valid JSON ({error})") from None
    return _from_json(data, str(path))


__all__ = [
    "PLAN_SCHEMA",
    "SAMPLE_HZ",
    "csv_columns",
    "plan_to_dict",
    "planned_trajectory_from_file",
    "sampled_path",
    "write_plan_csv",
    "write_plan_json",
]
