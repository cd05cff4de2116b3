"""The bulk CDR readers against rosbags' own serializer and deserializer (an independent implementation)."""

from __future__ import annotations

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from bsp_ros.bag.cdr import decode_fixed, decode_tf_message, encode_fixed
from bsp_ros.bag.topics import TF_TYPE, WRENCH_TYPE
from msg_adapters.tf import TransformSample, build_tf_message, read_tf_message

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)


def _tf_bytes(samples: list[TransformSample]) -> bytes:
    message = build_tf_message(lambda name: TYPESTORE.types[name], samples)
    return bytes(TYPESTORE.serialize_cdr(message, TF_TYPE))


@pytest.mark.parametrize(
    ("parent", "child"), [("world", "ft_sensor"), ("w", "a_much_longer_child_frame_id"), ("ab", "c")]
)
def test_tf_messages_read_as_rosbags_reads_them(parent: str, child: str) -> None:
    rng = np.random.default_rng(len(parent) + len(child))
    samples = [
        TransformSample(int(rng.integers(0, 2**40)), parent * k, f"{child}{k}", rng.normal(size=3), rng.normal(size=4))
        for k in range(1, 4)
    ]
    raw = _tf_bytes(samples)
    ours = decode_tf_message(raw)
    theirs = read_tf_message(TYPESTORE.deserialize_cdr(raw, TF_TYPE))
    assert ours is not None and len(ours) == len(theirs) == 3
    for a, b in zip(ours, theirs, strict=True):
        assert (a.t_ns, a.parent_frame, a.child_frame) == (b.t_ns, b.parent_frame, b.child_frame)
        assert np.array_equal(a.translation_m, b.translation_m) and np.array_equal(a.rotation_xyzw, b.rotation_xyzw)


def test_tf_bytes_that_do_not_fit_the_layout_are_left_to_rosbags() -> None:
    raw = _tf_bytes([TransformSample(5, "world", "sensor", np.ones(3), np.array([0.0, 0.0, 0.0, 1.0]))])
    assert decode_tf_message(raw[:-5]) is None  # truncated
    assert decode_tf_message(b"\x00\x00\x00\x00" + raw[4:]) is None  # big-endian encapsulation
    assert decode_tf_message(b"") is None


def test_wrench_messages_round_trip_byte_for_byte_with_rosbags() -> None:
    rng = np.random.default_rng(3)
    stamps = rng.integers(0, 2**40, size=5)
    values = rng.normal(size=(5, 6))
    rows = encode_fixed(stamps, "ft_sensor", values)
    for k in range(5):
        decoded = TYPESTORE.deserialize_cdr(rows[k].tobytes(), WRENCH_TYPE)
        assert decoded.header.frame_id == "ft_sensor"
        assert decoded.header.stamp.sec * 10**9 + decoded.header.stamp.nanosec == stamps[k]
        assert decoded.wrench.force.x == values[k, 0] and decoded.wrench.torque.z == values[k, 5]
    frames: dict[str, int] = {}
    batch = decode_fixed(rows.reshape(-1), np.arange(5) * rows.shape[1], np.full(5, rows.shape[1]), 6, frames)
    assert batch.ok.all() and frames == {"ft_sensor": 0}
    assert np.array_equal(batch.t_ns, stamps) and np.array_equal(batch.values, values)
