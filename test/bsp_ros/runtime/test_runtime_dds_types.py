"""Generated DDS types serialise byte-identically to rosbags' CDR and convert both ways."""

from __future__ import annotations

import random
from typing import Any

import numpy as np
import pytest
from rosbags.interfaces import Nodetype

from bsp_ros.errors import RuntimeBackendError
from bsp_ros.runtime import dds_types

_INT_RANGES = {
    "int8": (-128, 127),
    "int16": (-(2**15), 2**15 - 1),
    "int32": (-(2**31), 2**31 - 1),
    "int64": (-(2**63), 2**63 - 1),
    "uint8": (0, 255),
    "byte": (-128, 127),  # rosbags reads a scalar ROS byte as signed
    "char": (0, 255),
    "uint16": (0, 2**16 - 1),
    "uint32": (0, 2**32 - 1),
    "uint64": (0, 2**64 - 1),
}
_DTYPES = {"float32": np.float32, "float64": np.float64, "bool": np.bool_} | {
    name: (np.uint8 if name in ("byte", "char") else getattr(np, name)) for name in _INT_RANGES
}


def _scalar(rng: random.Random, base: str, bound: int) -> Any:
    if base == "string":
        text = rng.choice(["frame", "wörld/ß", "a", "ft_sensor", "x" * 7])
        return text[: bound or None]
    if base == "bool":
        return rng.random() < 0.5
    if base in ("float32", "float64"):
        value = rng.uniform(-1e3, 1e3)
        return float(np.float32(value)) if base == "float32" else value
    lo, hi = _INT_RANGES[base]
    return rng.choice([lo, hi, rng.randint(lo, hi)])


def _value(rng: random.Random, desc: Any) -> Any:
    kind = desc[0]
    if kind == Nodetype.BASE:
        return _scalar(rng, *desc[1])
    if kind == Nodetype.NAME:
        return _message(rng, desc[1])
    inner, size = desc[1]
    count = size if kind == Nodetype.ARRAY else rng.randint(1, 3)
    if inner[0] == Nodetype.BASE and inner[1][0] in ("byte", "char"):
        dtype = np.int8 if inner[1][0] == "byte" else np.uint8  # rosbags reads byte[] as int8
        return np.array([rng.randint(0, 255) for _ in range(count)], dtype=np.uint8).astype(dtype)
    items = [_value(rng, inner) for _ in range(count)]
    if inner[0] == Nodetype.BASE and inner[1][0] != "string":
        return np.array(items, dtype=_DTYPES[inner[1][0]])
    return items


def _message(rng: random.Random, type_name: str) -> Any:
    store = dds_types.typestore()
    fields = {name: _value(rng, desc) for name, desc in store.fielddefs[type_name][1]}
    return store.types[type_name](**fields)


def _assert_same(a: Any, b: Any) -> None:
    if isinstance(a, np.ndarray):
        np.testing.assert_array_equal(a, b)
        assert a.dtype == np.asarray(b).dtype
    elif isinstance(a, list):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            _assert_same(x, y)
    elif hasattr(a, "__msgtype__"):
        assert a.__msgtype__ == b.__msgtype__
        for name in a.__dataclass_fields__:
            if name != "__msgtype__":
                _assert_same(getattr(a, name), getattr(b, name))
    else:
        assert a == b and type(a) is type(b)


_EXTRA_TYPES = ("std_msgs/msg/Byte", "std_msgs/msg/Char", "std_msgs/msg/ByteMultiArray", "sensor_msgs/msg/Imu")


@pytest.mark.parametrize("type_name", dds_types.SUPPORTED_TYPES + _EXTRA_TYPES)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_cdr_is_byte_identical_to_rosbags(type_name: str, seed: int) -> None:
    store = dds_types.typestore()
    msg = _message(random.Random(f"{type_name}/{seed}"), type_name)
    expected = bytes(store.serialize_cdr(msg, type_name))
    dds_obj = dds_types.ros_to_dds(msg)
    assert type(dds_obj).__idl_typename__ == dds_types.dds_type_name(type_name)
    got = dds_obj.serialize()
    assert got[:4] == b"\x00\x01\x00\x00"
    assert got == expected
    # And back: the DDS decoder reads rosbags' bytes, and the converter restores the rosbags message.
    decoded = type(dds_obj).deserialize(expected)
    _assert_same(dds_types.dds_to_ros(decoded), msg)
    _assert_same(store.deserialize_cdr(got, type_name), msg)


def test_wrench_stamped_by_keyword() -> None:
    cls = dds_types.dds_class
    wrench = cls("geometry_msgs/msg/WrenchStamped")(
        header=cls("std_msgs/msg/Header")(
            stamp=cls("builtin_interfaces/msg/Time")(sec=-5, nanosec=999_999_999), frame_id="ft_sensor"
        ),
        wrench=cls("geometry_msgs/msg/Wrench")(
            force=cls("geometry_msgs/msg/Vector3")(x=-1.5, y=2.25, z=-9.81),
            torque=cls("geometry_msgs/msg/Vector3")(x=0.125, y=-0.5, z=3.0),
        ),
    )
    store = dds_types.typestore()
    ros = dds_types.dds_to_ros(wrench)
    assert bytes(store.serialize_cdr(ros, "geometry_msgs/msg/WrenchStamped")) == wrench.serialize()
    assert ros.wrench.force.z == -9.81 and ros.header.frame_id == "ft_sensor"


def test_type_names_and_hash() -> None:
    assert dds_types.dds_type_name("tf2_msgs/msg/TFMessage") == "tf2_msgs::msg::dds_::TFMessage_"
    # The published Jazzy hash of std_msgs/msg/String.
    assert dds_types.type_hash("std_msgs/msg/String") == (
        "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
    )
    assert dds_types.dds_class("std_msgs/msg/String") is dds_types.dds_class("std_msgs/msg/String")
    with pytest.raises(RuntimeBackendError, match="nope_msgs/msg/X"):
        dds_types.dds_class("nope_msgs/msg/X")
    with pytest.raises(RuntimeBackendError, match="bad"):
        dds_types.dds_type_name("bad")


def test_plain_sequences_replaces_numpy_arrays() -> None:
    # cyclonedds writes np.zeros(1) as a count without data: publishers must hand it lists.
    cls = dds_types.dds_class
    header = cls("std_msgs/msg/Header")(stamp=cls("builtin_interfaces/msg/Time")(sec=1, nanosec=2), frame_id="f")
    msg = cls("sensor_msgs/msg/JointState")(
        header=header, name=["a"], position=np.zeros(1), velocity=[], effort=np.array([-1.5])
    )
    plain = dds_types.plain_sequences(msg, "sensor_msgs/msg/JointState")
    assert plain is not msg and plain.position == [0.0] and plain.effort == [-1.5]
    assert isinstance(msg.position, np.ndarray)  # the caller's object is left alone
    store = dds_types.typestore()
    assert plain.serialize() == bytes(store.serialize_cdr(dds_types.dds_to_ros(plain), "sensor_msgs/msg/JointState"))
    lists = dds_types.plain_sequences(plain, "sensor_msgs/msg/JointState")
    assert lists is plain
    wrench = dds_types.ros_to_dds(_message(random.Random(0), "geometry_msgs/msg/WrenchStamped"))
    assert dds_types.plain_sequences(wrench, "geometry_msgs/msg/WrenchStamped") is wrench
