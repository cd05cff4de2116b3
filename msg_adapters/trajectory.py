"""``trajectory_msgs/msg/JointTrajectory`` and ``nav_msgs/msg/Path`` <-> numpy (a planned protocol)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from msg_adapters._types import TypeLookup, float_sequence, string_sequence
from msg_adapters.stamps import NS_PER_S, build_header, read_header


def build_duration(types: TypeLookup, t_s: float) -> Any:
    """Build a ``builtin_interfaces/msg/Duration`` of ``t_s`` >= 0 seconds (nanosecond resolution)."""
    if not math.isfinite(t_s) or t_s < 0:
        raise ValueError(f"a time from start must be finite and >= 0 s, got {t_s!r}")
    sec, nanosec = divmod(round(t_s * NS_PER_S), NS_PER_S)
    return types("builtin_interfaces/msg/Duration")(sec=int(sec), nanosec=int(nanosec))


def build_joint_trajectory(
    types: TypeLookup,
    t_ns: int,
    joint_names: Sequence[str],
    t_s: npt.ArrayLike,
    q_rad: npt.ArrayLike,
    qdot_rad_s: npt.ArrayLike,
    frame_id: str = "",
) -> Any:
    """Build a ``trajectory_msgs/msg/JointTrajectory``: one point per time.

    Parameters
    ----------
    types : message class lookup.
    t_ns : header stamp (the trajectory's start), ns.
    joint_names : (n,) e.g. ``("shoulder", "elbow", "wrist")``.
    t_s : (N,) time from start of each point, s.
    q_rad, qdot_rad_s : (N, n) positions (rad) and velocities (rad/s).
    frame_id : header frame (empty for joint space).

    Raises
    ------
    ValueError
        Mismatched shapes.
    """
    times = np.asarray(t_s, dtype=np.float64).reshape(-1)
    positions = np.asarray(q_rad, dtype=np.float64)
    velocities = np.asarray(qdot_rad_s, dtype=np.float64)
    shape = (times.size, len(joint_names))
    if positions.shape != shape or velocities.shape != shape:
        raise ValueError(f"positions and velocities must be {shape}, got {positions.shape} and {velocities.shape}")
    point_cls = types("trajectory_msgs/msg/JointTrajectoryPoint")
    cls = types("trajectory_msgs/msg/JointTrajectory")
    points = [
        point_cls(
            positions=float_sequence(point_cls, positions[i]),
            velocities=float_sequence(point_cls, velocities[i]),
            accelerations=float_sequence(point_cls, []),
            effort=float_sequence(point_cls, []),
            time_from_start=build_duration(types, float(times[i])),
        )
        for i in range(times.size)
    ]
    return cls(header=build_header(types, t_ns, frame_id), joint_names=string_sequence(joint_names), points=points)


def read_joint_trajectory(msg: Any) -> tuple[tuple[str, ...], np.ndarray, np.ndarray, np.ndarray]:
    """Read a ``JointTrajectory``: names, (N,) times from start (s), (N, n) positions, (N, n) velocities."""
    names = tuple(str(n) for n in msg.joint_names)
    times = np.array([p.time_from_start.sec + p.time_from_start.nanosec / NS_PER_S for p in msg.points])
    positions = np.array([np.asarray(p.positions, dtype=np.float64) for p in msg.points]).reshape(-1, len(names))
    velocities = np.array([np.asarray(p.velocities, dtype=np.float64) for p in msg.points]).reshape(-1, len(names))
    return names, times, positions, velocities


def build_handle_path(
    types: TypeLookup, t_ns: int, frame_id: str, t_s: npt.ArrayLike, poses_yzp: npt.ArrayLike, plane_x_m: float = 0.0
) -> Any:
    """Build a ``nav_msgs/msg/Path`` of handle poses in the sagittal plane.

    Parameters
    ----------
    types : message class lookup.
    t_ns : stamp of the path and of its start, ns; each pose is stamped ``t_ns + t_s``.
    frame_id : the poses' frame (``world``).
    t_s : (N,) time of each pose from the start, s.
    poses_yzp : (N, 3) ``[y (m), z (m), pitch (rad)]``; pitch is a rotation about +x.
    plane_x_m : x of the movement plane (the shoulder's x), m.
    """
    times = np.asarray(t_s, dtype=np.float64).reshape(-1)
    poses = np.asarray(poses_yzp, dtype=np.float64)
    if poses.shape != (times.size, 3):
        raise ValueError(f"poses must be ({times.size}, 3) [y, z, pitch], got {poses.shape}")
    pose_stamped = types("geometry_msgs/msg/PoseStamped")
    pose_cls = types("geometry_msgs/msg/Pose")
    point_cls = types("geometry_msgs/msg/Point")
    quaternion_cls = types("geometry_msgs/msg/Quaternion")
    stamped = []
    for t, (y, z, pitch) in zip(times, poses, strict=True):
        half = 0.5 * float(pitch)
        pose = pose_cls(
            position=point_cls(x=float(plane_x_m), y=float(y), z=float(z)),
            orientation=quaternion_cls(x=math.sin(half), y=0.0, z=0.0, w=math.cos(half)),
        )
        stamped.append(pose_stamped(header=build_header(types, t_ns + round(t * NS_PER_S), frame_id), pose=pose))
    return types("nav_msgs/msg/Path")(header=build_header(types, t_ns, frame_id), poses=stamped)


def read_handle_path(msg: Any) -> tuple[np.ndarray, np.ndarray]:
    """Read a ``Path`` of handle poses: (N,) stamps (ns) and (N, 3) ``[y, z, pitch]`` (pitch about +x)."""
    stamps, rows = [], []
    for item in msg.poses:
        stamps.append(read_header(item.header)[0])
        q = item.pose.orientation
        rows.append((item.pose.position.y, item.pose.position.z, 2.0 * math.atan2(q.x, q.w)))
    return np.array(stamps, dtype=np.int64), np.array(rows, dtype=np.float64).reshape(-1, 3)
