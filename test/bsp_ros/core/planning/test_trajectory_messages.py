"""msg_adapters.trajectory: JointTrajectory and Path built with rosbags' classes, serialised and read back."""

from __future__ import annotations

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from bsp_ros.core.planning import Plan
from bsp_ros.core.planning.files import sampled_path
from msg_adapters.trajectory import (
    build_handle_path,
    build_joint_trajectory,
    read_handle_path,
    read_joint_trajectory,
)

START_NS = 1_700_000_000_123_456_789


@pytest.fixture(scope="module")
def typestore():
    return get_typestore(Stores.ROS2_JAZZY)


def test_joint_trajectory_round_trips_through_cdr(plan: Plan, typestore) -> None:
    samples = sampled_path(plan, 2.0)
    msg = build_joint_trajectory(
        lambda n: typestore.types[n],
        START_NS,
        ("shoulder", "elbow", "wrist"),
        samples["t_s"],
        samples["q_rad"],
        samples["qdot_rad_s"],
    )
    raw = typestore.serialize_cdr(msg, "trajectory_msgs/msg/JointTrajectory")
    names, t_s, q, qdot = read_joint_trajectory(typestore.deserialize_cdr(raw, "trajectory_msgs/msg/JointTrajectory"))
    assert names == ("shoulder", "elbow", "wrist")
    np.testing.assert_allclose(t_s, samples["t_s"], atol=1e-9)
    np.testing.assert_array_equal(q, samples["q_rad"])
    np.testing.assert_array_equal(qdot, samples["qdot_rad_s"])


def test_handle_path_round_trips_through_cdr(plan: Plan, typestore) -> None:
    samples = sampled_path(plan, 1.0)
    msg = build_handle_path(lambda n: typestore.types[n], START_NS, "world", samples["t_s"], samples["handle"], 0.2)
    raw = typestore.serialize_cdr(msg, "nav_msgs/msg/Path")
    back = typestore.deserialize_cdr(raw, "nav_msgs/msg/Path")
    stamps, poses = read_handle_path(back)
    assert back.header.frame_id == "world"
    assert back.poses[0].pose.position.x == 0.2
    np.testing.assert_array_equal(stamps - START_NS, np.round(samples["t_s"] * 1e9).astype(np.int64))
    np.testing.assert_allclose(poses, samples["handle"], atol=1e-12)


def test_mismatched_shapes_are_refused(typestore) -> None:
    with pytest.raises(ValueError, match="positions and velocities"):
        build_joint_trajectory(lambda n: typestore.types[n], START_NS, ("shoulder", "elbow"), [0.0], [[0.0]], [[0.0]])
