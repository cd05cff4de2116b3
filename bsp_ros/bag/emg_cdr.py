"""The EMG envelope message (``std_msgs/msg/Float32MultiArray``) as CDR bytes, without a type store.

docs/contract.md fixes its shape: one value per channel in ``data``; ``layout.dim[0].label`` holds the channel
names joined by commas, ``layout.dim[0].size`` their count. The message carries no stamp: a bag's log time is its
time.
"""

from __future__ import annotations

import struct

import numpy as np

__all__ = ["EMG_TYPE", "decode_envelope", "encode_envelope"]

EMG_TYPE = "std_msgs/msg/Float32MultiArray"

# Plain little-endian CDR (XCDR1), as rosbag2 records it.
_CDR_LE = b"\x00\x01\x00\x00"


def _pad(length: int) -> bytes:
    """Zero bytes that align ``length`` (bytes after the encapsulation header) to 4."""
    return b"\x00" * (-length % 4)


def encode_envelope(channels: tuple[str, ...], values: np.ndarray) -> bytes:
    """One message's CDR bytes: ``values`` (C,) as ``data``, ``channels`` (C,) joined by commas as the one dimension's
    label (size and stride C, data offset 0)."""
    label = ",".join(channels).encode("utf-8") + b"\x00"
    body = struct.pack("<II", 1, len(label)) + label
    body += _pad(len(body))
    count = len(channels)
    body += struct.pack("<III", count, count, 0)
    data = np.asarray(values, dtype="<f4")
    body += struct.pack("<I", data.size) + data.tobytes()
    return _CDR_LE + body


def decode_envelope(raw: bytes) -> tuple[tuple[str, ...], np.ndarray] | None:
    """The channel names (the first dimension's label split at commas; ``()`` without a dimension) and the values
    (C,) float64 of one message; None where the bytes are no little-endian CDR Float32MultiArray."""
    if len(raw) < 12 or raw[:4] != _CDR_LE:
        return None
    try:
        at = 4
        (n_dims,) = struct.unpack_from("<I", raw, at)
        at += 4
        label = ""
        for k in range(n_dims):
            (length,) = struct.unpack_from("<I", raw, at)
            at += 4
            text = raw[at : at + length]
            if len(text) != length or not text.endswith(b"\x00"):
                return None
            if k == 0:
                label = text[:-1].decode("utf-8")
            at += length
            at += -(at - 4) % 4
            at += 8  # size, stride
        at += 4  # data_offset
        (count,) = struct.unpack_from("<I", raw, at)
        at += 4
        if len(raw) < at + 4 * count:
            return None
        values = np.frombuffer(raw, dtype="<f4", count=count, offset=at).astype(np.float64)
    except (struct.error, UnicodeDecodeError):
        return None
    channels = tuple(name.strip() for name in label.split(",")) if label else ()
    return channels, values
