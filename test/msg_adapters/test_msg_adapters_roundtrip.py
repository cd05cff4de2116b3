"""msg_adapters: message -> numpy -> message round trips on rosbags types, and duck-typed plain objects."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

import msg_adapters as ma
from bsp_ros.core.streams import MarkerSeries, WrenchSeries

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)


def types(name: str) -> type:
    return TYPESTORE.types[name]  # type: ignore[no-any-return]


def cdr(msg: Any) -> bytes:
    return bytes(TYPESTORE.serialize_cdr(msg, msg.__msgtype__))


def roundtrip(msg: Any) -> Any:
    """Serialize and deserialize with rosbags: the builder's output is a valid message of its type."""
    return TYPESTORE.deserialize_cdr(cdr(msg), msg.__msgtype__)


@pytest.mark.parametrize("t_ns", [1, 999_999_999, 1_000_000_000, 1_700_000_000_123_456_789, -1, -1_500_000_000])
def test_stamp_roundtrip(t_ns: int) -> None:
    msg = ma.build_time(types, t_ns)
    assert 0 <= msg.nanosec < 1_000_000_000
    assert ma.stamp_to_ns(msg) == t_ns
    assert ma.stamp_to_ns(roundtrip(msg)) == t_ns


def test_stamp_out_of_int32_range_is_refused() -> None:
    with pytest.raises(ValueError, match="int32"):
        ma.ns_to_sec_nanosec(2**31 * 1_000_000_000)


def test_wrench_roundtrip_bit_exact() -> None:
    sample = ma.WrenchSample(
        1_700_000_000_000_000_123, "ft_sensor", np.array([1.5, -2.0, np.nan]), np.array([0.1, np.inf, -0.0])
    )
    msg = roundtrip(ma.build_wrench_stamped(types, sample))
    back = ma.read_wrench_stamped(msg)
    assert back.t_ns == sample.t_ns and back.frame_id == "ft_sensor"
    assert back.force_n.tobytes() == sample.force_n.tobytes()
    assert back.torque_nm.tobytes() == sample.torque_nm.tobytes()
    assert cdr(ma.build_wrench_stamped(types, back)) == cdr(msg)


def test_pose_roundtrip() -> None:
    sample = ma.PoseSample(5, "world", np.array([0.1, 0.2, 0.3]), np.array([0.0, 0.0, 0.6, 0.8]))
    msg = roundtrip(ma.build_pose_stamped(types, sample))
    back = ma.read_pose_stamped(msg)
    assert back.t_ns == 5 and back.frame_id == "world"
    np.testing.assert_array_equal(back.position_m, sample.position_m)
    np.testing.assert_array_equal(back.orientation_xyzw, sample.orientation_xyzw)
    assert cdr(ma.build_pose_stamped(types, back)) == cdr(msg)


def test_series_roundtrip() -> None:
    rng = np.random.default_rng(1)
    series = WrenchSeries(np.arange(1, 6, dtype=np.int64) * 10, rng.normal(size=(5, 3)), rng.normal(size=(5, 3)), "ft")
    msgs = [ma.build_wrench_stamped(types, s) for s in ma.wrench_samples_from_series(series)]
    back = ma.wrench_series_from_messages(roundtrip(m) for m in msgs)
    assert back.frame_id == "ft"
    np.testing.assert_array_equal(back.t_ns, series.t_ns)
    np.testing.assert_array_equal(back.force_n, series.force_n)
    np.testing.assert_array_equal(back.torque_nm, series.torque_nm)
    markers = MarkerSeries(np.array([3, 4], dtype=np.int64), rng.normal(size=(2, 3)))
    poses = [ma.build_pose_stamped(types, s) for s in ma.pose_samples_from_series(markers)]
    got = ma.marker_series_from_messages(poses)
    np.testing.assert_array_equal(got.position_m, markers.position_m)
    empty = ma.wrench_series_from_messages([])
    assert empty.t_ns.shape == (0,) and empty.force_n.shape == (0, 3)


def test_wrench_series_refuses_mixed_frames() -> None:
    a = ma.build_wrench_stamped(types, ma.WrenchSample(1, "a", np.zeros(3), np.zeros(3)))
    b = ma.build_wrench_stamped(types, ma.WrenchSample(2, "b", np.zeros(3), np.zeros(3)))
    with pytest.raises(ValueError, match="several frame ids"):
        ma.wrench_series_from_messages([a, b])


def test_tf_roundtrip_and_chain() -> None:
    q_ab = ma.quaternion_from_matrix(np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]))
    samples = [
        ma.TransformSample(7, "world", "base", np.array([1.0, 2.0, 3.0]), q_ab),
        ma.TransformSample(7, "base", "ft_sensor", np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])),
    ]
    msg = roundtrip(ma.build_tf_message(types, samples))
    back = ma.read_tf_message(msg)
    assert [(s.parent_frame, s.child_frame) for s in back] == [("world", "base"), ("base", "ft_sensor")]
    np.testing.assert_array_equal(back[0].translation_m, [1.0, 2.0, 3.0])
    assert cdr(ma.build_tf_message(types, back)) == cdr(msg)
    r = ma.rotation_between(back, "world", "ft_sensor")
    assert r is not None
    expected = ma.matrix_from_quaternion(q_ab) @ np.diag([1.0, -1.0, -1.0])
    np.testing.assert_allclose(r, expected, atol=1e-12)
    # Going the other way gives the inverse; a sibling frame goes through the common parent.
    r_inv = ma.rotation_between(back, "ft_sensor", "world")
    assert r_inv is not None
    np.testing.assert_allclose(r_inv, expected.T, atol=1e-12)
    sibling = [*back, ma.TransformSample(7, "base", "camera", np.zeros(3), q_ab)]
    r_cam = ma.rotation_between(sibling, "camera", "ft_sensor")
    assert r_cam is not None
    np.testing.assert_allclose(r_cam, ma.matrix_from_quaternion(q_ab).T @ np.diag([1.0, -1.0, -1.0]), atol=1e-12)
    assert ma.rotation_between(back, "world", "elsewhere") is None
    np.testing.assert_array_equal(ma.rotation_between([], "world", "world"), np.eye(3))


def test_rotation_helpers() -> None:
    rng = np.random.default_rng(3)
    q = rng.normal(size=4)
    r = ma.matrix_from_quaternion(q)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    q2 = ma.quaternion_from_matrix(r)
    assert q2[3] >= 0
    np.testing.assert_allclose(ma.matrix_from_quaternion(q2), r, atol=1e-12)
    with pytest.raises(ValueError):
        ma.matrix_from_quaternion([0.0, 0.0, 0.0, 0.0])
    with pytest.raises(ValueError):
        ma.quaternion_from_matrix(np.diag([1.0, 1.0, -1.0]))


def test_matrix_from_quaternion_equals_scipy_rotation() -> None:
    from scipy.spatial.transform import Rotation

    quaternions = np.random.default_rng(11).normal(size=(50, 4)) * 3.0  # not normalised: both normalise
    for q in quaternions:
        np.testing.assert_allclose(ma.matrix_from_quaternion(q), Rotation.from_quat(q).as_matrix(), atol=1e-12)


def test_joint_state_roundtrip() -> None:
    sample = ma.JointStateSample(
        9, "arm", ("shoulder", "elbow"), np.array([0.1, 0.2]), np.array([]), np.array([1.0, 2.0])
    )
    msg = roundtrip(ma.build_joint_state(types, sample))
    back = ma.read_joint_state(msg)
    assert back.names == ("shoulder", "elbow") and back.velocity.size == 0
    np.testing.assert_array_equal(back.position, sample.position)
    np.testing.assert_array_equal(back.effort, sample.effort)
    assert cdr(ma.build_joint_state(types, back)) == cdr(msg)
    with pytest.raises(ValueError, match="position"):
        ma.build_joint_state(types, ma.JointStateSample(1, "", ("a",), np.array([1.0, 2.0])))


def test_inertia_roundtrip() -> None:
    tensor = np.array([[1.0, 0.1, 0.2], [0.1, 2.0, 0.3], [0.2, 0.3, 3.0]])
    sample = ma.InertiaSample(11, "forearm", 1.16, np.array([0.112, 0.0, 0.0]), tensor)
    msg = roundtrip(ma.build_inertia_stamped(types, sample))
    back = ma.read_inertia_stamped(msg)
    assert back.mass_kg == 1.16 and back.frame_id == "forearm"
    np.testing.assert_array_equal(back.inertia_kgm2, tensor)
    assert cdr(ma.build_inertia_stamped(types, back)) == cdr(msg)


def test_diagnostics_roundtrip() -> None:
    status = ma.DiagnosticStatusData.with_values(
        1, "bsp/identifier", "poor excitation", "cell-1", {"n": 3, "cond": 12.5}
    )
    sample = ma.DiagnosticArraySample(13, "", (status, ma.DiagnosticStatusData(0, "bsp/reader")))
    msg = roundtrip(ma.build_diagnostic_array(types, sample))
    back = ma.read_diagnostic_array(msg)
    assert back == sample
    assert cdr(ma.build_diagnostic_array(types, back)) == cdr(msg)


# Duck-typed plain objects: what rclpy classes look like to the adapters.


class _Plain:
    """A keyword-constructed record with the given fields (stand-in for rclpy/IdlStruct classes)."""

    def __init__(self, **fields: Any) -> None:
        self.__dict__.update(fields)

    def __eq__(self, other: object) -> bool:
        return type(self) is type(other) and self.__dict__ == other.__dict__


class _RclpyLikeStatus(_Plain):
    OK = b"\x00"  # rclpy holds `byte` constants and fields as bytes


def plain_types(name: str) -> type:
    if name == "diagnostic_msgs/msg/DiagnosticStatus":
        return _RclpyLikeStatus
    return type(name.rsplit("/", 1)[-1], (_Plain,), {})


def test_plain_objects_read_and_build() -> None:
    stamp = SimpleNamespace(sec=2, nanosec=5)
    msg = SimpleNamespace(
        header=SimpleNamespace(stamp=stamp, frame_id="ft"),
        wrench=SimpleNamespace(force=SimpleNamespace(x=1.0, y=2.0, z=3.0), torque=SimpleNamespace(x=4.0, y=5.0, z=6.0)),
    )
    sample = ma.read_wrench_stamped(msg)
    assert sample.t_ns == 2_000_000_005
    built = ma.build_wrench_stamped(plain_types, sample)
    assert type(built).__name__ == "WrenchStamped"
    assert ma.read_wrench_stamped(built).force_n.tolist() == [1.0, 2.0, 3.0]
    assert isinstance(built.wrench.force.x, float) and isinstance(built.header.stamp.sec, int)


def test_plain_objects_sequences_and_byte_levels() -> None:
    js = ma.build_joint_state(plain_types, ma.JointStateSample(1, "", ("a", "b"), np.array([1.0, 2.0])))
    assert js.position == [1.0, 2.0] and isinstance(js.position, list)
    assert ma.read_joint_state(js).position.tolist() == [1.0, 2.0]
    diag = ma.build_diagnostic_array(plain_types, ma.DiagnosticArraySample(1, "", (ma.DiagnosticStatusData(2, "x"),)))
    assert diag.status[0].level == b"\x02"
    assert ma.read_diagnostic_array(diag).status[0].level == 2
