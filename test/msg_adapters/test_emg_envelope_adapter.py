"""msg_adapters' EMG envelope against the bag's own CDR coder (an independent implementation of the same shape)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from bsp_ros.bag.emg_cdr import decode_envelope, encode_envelope
from msg_adapters.emg import EMG_TYPE, build_envelope, read_envelope

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
CHANNELS = ("biceps", "triceps", "deltoid_anterior")


def types(name: str) -> Any:
    return TYPESTORE.types[name]


def test_a_built_envelope_is_the_bag_coder_s_bytes_and_reads_back() -> None:
    values = np.array([2.5, 0.125, 3.0e-6])
    msg = build_envelope(types, CHANNELS, values)
    raw = bytes(TYPESTORE.serialize_cdr(msg, EMG_TYPE))
    assert raw == encode_envelope(CHANNELS, values)
    channels, back = read_envelope(TYPESTORE.deserialize_cdr(encode_envelope(CHANNELS, values), EMG_TYPE))
    assert channels == CHANNELS
    np.testing.assert_array_equal(back, values.astype(np.float32))
    decoded = decode_envelope(raw)
    assert decoded is not None and decoded[0] == channels


def test_no_dimension_reads_as_no_channels_and_a_bad_envelope_is_not_built() -> None:
    bare = TYPESTORE.types[EMG_TYPE](
        layout=TYPESTORE.types["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0),
        data=np.ones(2, dtype=np.float32),
    )
    channels, values = read_envelope(bare)
    assert channels == () and values.tolist() == [1.0, 1.0]
    with pytest.raises(ValueError, match="one value per channel"):
        build_envelope(types, CHANNELS, np.ones(2))
    with pytest.raises(ValueError, match="no comma"):
        build_envelope(types, ("a,b",), np.ones(1))
