"""The wrench frame's rotation: TF tree or TransformStamped topic, else the stated quaternion (the cell's)."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core.simulation import rotation_from_rpy_deg
from bsp_ros.live.online.frames import NO_TRANSFORM, WrenchFrames, rotation_from_quaternion_xyzw
from msg_adapters.rotation import quaternion_from_matrix
from msg_adapters.tf import TransformSample

R_SENSOR = rotation_from_rpy_deg(180.0, 0.0, 30.0)


def _transform(rotation: np.ndarray, child: str = "ft_sensor") -> TransformSample:
    return TransformSample(0, "world", child, np.zeros(3), quaternion_from_matrix(rotation))


def test_quaternion_parameter_gives_the_rotation_and_refuses_a_non_unit_one() -> None:
    np.testing.assert_allclose(rotation_from_quaternion_xyzw(quaternion_from_matrix(R_SENSOR)), R_SENSOR, atol=1e-12)
    with pytest.raises(ValueError, match="norm"):
        rotation_from_quaternion_xyzw([0.0, 0.0, 0.0, 2.0])
    with pytest.raises(ValueError, match="4 finite"):
        rotation_from_quaternion_xyzw([0.0, 0.0, 1.0])


def test_without_tf_every_frame_but_world_takes_the_parameter() -> None:
    frames = WrenchFrames("world", use_tf=False, parameter_rotation=R_SENSOR, tf_wait_s=2.0)
    np.testing.assert_allclose(frames.rotation_for("ft_sensor", 0), R_SENSOR)
    np.testing.assert_allclose(frames.rotation_for("world", 0), np.eye(3))
    assert frames.sources == {"ft_sensor": "parameter", "world": "world"}


def test_with_tf_the_transform_wins_and_a_change_is_reported() -> None:
    frames = WrenchFrames("world", use_tf=True, parameter_rotation=np.eye(3), tf_wait_s=2.0)
    frames.on_transforms([_transform(R_SENSOR)])
    np.testing.assert_allclose(frames.rotation_for("ft_sensor", 0), R_SENSOR, atol=1e-12)
    assert frames.sources["ft_sensor"] == "tf"
    turned = rotation_from_rpy_deg(180.0, 0.0, 45.0)
    assert frames.on_transforms([_transform(turned)]) == ["ft_sensor"]
    np.testing.assert_allclose(frames.rotation_for("ft_sensor", 0), turned, atol=1e-12)


def test_transforms_from_the_topic_are_said_to_come_from_it() -> None:
    # As a bag read the same way says (rotation_source "topic"), not "tf": the TransformStamped topic without tf2_msgs.
    frames = WrenchFrames("world", use_tf=True, parameter_rotation=np.eye(3), tf_wait_s=2.0, transform_source="topic")
    frames.on_transforms([_transform(R_SENSOR)])
    rotation = frames.rotation_for("ft_sensor", 0)
    assert rotation is not None and np.allclose(rotation, R_SENSOR, atol=1e-12)
    assert frames.sources["ft_sensor"] == "topic"
    turned = rotation_from_rpy_deg(180.0, 0.0, 45.0)
    assert frames.on_transforms([_transform(turned)]) == ["ft_sensor"]  # a re-mounted sensor: still the topic's
    assert frames.sources["ft_sensor"] == "topic"
    waited = WrenchFrames("world", use_tf=True, parameter_rotation=R_SENSOR, tf_wait_s=2.0, transform_source="topic")
    assert waited.rotation_for("ft_sensor", 0) is None
    waited.rotation_for("ft_sensor", 3_000_000_000)
    assert waited.sources["ft_sensor"] == NO_TRANSFORM
    waited.on_transforms([_transform(R_SENSOR)])  # the transform came late: it replaces the stated rotation
    assert waited.sources["ft_sensor"] == "topic"
    # A sensor turning with the handle: rotated per wrench stamp, from the topic.
    turning = WrenchFrames("world", use_tf=True, parameter_rotation=np.eye(3), tf_wait_s=2.0, transform_source="topic")
    quaternions = [quaternion_from_matrix(rotation_from_rpy_deg(180.0, 0.0, yaw)) for yaw in (30.0, 40.0)]
    turning.on_transforms(
        [TransformSample(k * 10**9, "world", "ft_sensor", np.zeros(3), quaternions[k]) for k in (0, 1)]
    )
    halfway = rotation_from_rpy_deg(180.0, 0.0, 35.0)
    rotation = turning.rotation_for("ft_sensor", 0, 500_000_000)  # between the two: slerped
    assert rotation is not None and np.allclose(rotation, halfway, atol=1e-9)
    assert turning.sources == {"ft_sensor": "topic (per sample)"}


def test_with_tf_a_frame_without_transform_waits_then_takes_the_stated_rotation() -> None:
    frames = WrenchFrames("world", use_tf=True, parameter_rotation=R_SENSOR, tf_wait_s=2.0)
    assert frames.rotation_for("ft_sensor", 1_000_000_000) is None
    assert frames.rotation_for("ft_sensor", 2_500_000_000) is None
    np.testing.assert_allclose(frames.rotation_for("ft_sensor", 3_000_000_001), R_SENSOR)
    assert frames.sources["ft_sensor"] == NO_TRANSFORM
    # A transform that comes later replaces it (the same rotation: the source changes, nothing restarts).
    assert frames.on_transforms([_transform(R_SENSOR)]) == []
    assert frames.sources["ft_sensor"] == "tf" and not frames.disagreement_deg


def test_a_transform_off_the_stated_rotation_is_used_and_its_angle_noted() -> None:
    frames = WrenchFrames("world", use_tf=True, parameter_rotation=R_SENSOR, tf_wait_s=2.0)
    mounted = rotation_from_rpy_deg(180.0, 0.0, 30.0 + 12.5)  # 12.5 deg about z from the stated mounting
    frames.on_transforms([_transform(mounted)])
    np.testing.assert_allclose(frames.rotation_for("ft_sensor", 0), mounted, atol=1e-12)
    assert frames.disagreement_deg["ft_sensor"] == pytest.approx(12.5, abs=1e-6)
    near = rotation_from_rpy_deg(180.0, 0.0, 30.5)  # within a degree: not a disagreement
    assert frames.on_transforms([_transform(near)]) == ["ft_sensor"]
    assert frames.rotation_for("ft_sensor", 0) is not None and not frames.disagreement_deg


def test_the_wrench_frame_source_parameter_picks_tf_a_topic_or_the_quaternion() -> None:
    from bsp_ros.live.online.frames import frame_source

    assert frame_source("auto", True, "t").tf
    auto = frame_source("auto", False, "ft_sensor/transform")  # no tf2_msgs: the TransformStamped topic
    assert auto.topic and not auto.tf and "ft_sensor/transform" in auto.description
    assert not frame_source("parameter", False, "t").transforms
    topic = frame_source("topic", False, "ft_sensor/transform")
    assert topic.topic and not topic.tf and topic.transforms and "ft_sensor/transform" in topic.description
    assert frame_source("parameter", True, "t").description == "parameter wrench_frame_rotation_xyzw"
    with pytest.raises(ValueError, match="tf2_msgs/msg/TFMessage is not installed"):
        frame_source("tf", False, "t")
