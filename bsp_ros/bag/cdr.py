"""Vectorised CDR for fixed-layout stamped messages (WrenchStamped, PoseStamped): bytes <-> numpy in bulk.

Layout (little-endian XCDR1, as rosbags, Cyclone DDS and rmw write it): a 4-byte encapsulation header
``00 01 00 00``, then ``int32 sec, uint32 nanosec, uint32 L, L bytes frame_id (NUL-terminated)``,
padding to a multiple of 8 counted from the end of the encapsulation header, then ``k`` float64.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np

from bsp_ros.bag.byte_windows import byte_windows
from bsp_ros.bag.topics import POSE_TYPE, WRENCH_TYPE
from bsp_ros.errors import InputError
from msg_adapters.tf import TransformSample

#: Message type -> number of float64 after the header (Wrench: force, torque; Pose: position, xyzw).
FIXED_LAYOUT_FLOATS: dict[str, int] = {WRENCH_TYPE: 6, POSE_TYPE: 7}

_STAMP = np.dtype([("sec", "<i4"), ("nanosec", "<u4")])
_NS = np.int64(1_000_000_000)
_HEADER = 16  # encapsulation (4) + sec (4) + nanosec (4) + string length (4)


@dataclass
class FixedBatch:
    """Messages of one channel decoded by the fast path.

    Attributes
    ----------
    t_ns : (n,) int64 header stamps.
    values : (n, k) float64, bit-exact copies of the message floats.
    frame_index : (n,) int64 index into the decoder's frame list.
    ok : (n,) bool, False where the bytes do not fit the layout (decode those another way).
    """

    t_ns: np.ndarray
    values: np.ndarray
    frame_index: np.ndarray
    ok: np.ndarray


def decode_fixed(
    buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, n_floats: int, frames: dict[str, int]
) -> FixedBatch:
    """Decode messages ``buf[offsets[i]:offsets[i] + lengths[i]]`` of a fixed-layout type in bulk.

    Parameters
    ----------
    buf : (B,) uint8, the bytes holding the messages (e.g. one MCAP chunk).
    offsets, lengths : (n,) int64, where each serialized message starts and its length in bytes.
    n_floats : float64 count after the header (6 WrenchStamped, 7 PoseStamped).
    frames : frame id -> index, extended with new frame ids.

    Returns
    -------
    FixedBatch ; rows with ``ok`` False hold zeros.
    """
    n = offsets.size
    t_ns = np.zeros(n, dtype=np.int64)
    values = np.zeros((n, n_floats), dtype=np.float64)
    frame_index = np.full(n, -1, dtype=np.int64)
    ok = lengths >= _HEADER + 1 + 8 * n_floats
    idx = np.flatnonzero(ok)
    if idx.size:
        head = byte_windows(buf, offsets[idx], _HEADER)
        little = (head[:, 0] == 0) & (head[:, 1] == 1)
        str_len = head[:, 12:16].copy().view("<u4")[:, 0].astype(np.int64)
        float_at = 4 + ((12 + str_len + 7) & ~np.int64(7))
        fits = little & (str_len >= 1) & (float_at + 8 * n_floats <= lengths[idx])
        ok[idx[~fits]] = False
        keep, head, str_len, float_at = idx[fits], head[fits], str_len[fits], float_at[fits]
        stamps = head[:, 4:12].copy().view(_STAMP)[:, 0]
        t_ns[keep] = stamps["sec"].astype(np.int64) * _NS + stamps["nanosec"].astype(np.int64)
        starts = offsets[keep]
        values[keep] = byte_windows(buf, starts + float_at, 8 * n_floats).view("<f8")
        for size in np.unique(str_len):
            group = str_len == size
            text = byte_windows(buf, starts[group] + _HEADER, int(size))
            terminated = text[:, -1] == 0
            ok[keep[group][~terminated]] = False
            names = text[terminated, :-1]
            if names.shape[0] and (names == names[0]).all():  # the usual case: one frame id
                rows, inverse = names[:1], np.zeros(names.shape[0], dtype=np.int64)
            else:
                rows, inverse = np.unique(names, axis=0, return_inverse=True)
            codes = np.empty(rows.shape[0], dtype=np.int64)
            for r, row in enumerate(rows):
                name = row.tobytes().decode("utf-8", errors="replace")
                codes[r] = frames.setdefault(name, len(frames))
            frame_index[keep[group][terminated]] = codes[np.asarray(inverse).reshape(-1)]
    return FixedBatch(t_ns, values, frame_index, ok)


def encode_fixed(t_ns: np.ndarray, frame_id: str, values: np.ndarray) -> np.ndarray:
    """Serialize stamped fixed-layout messages in bulk, byte-identical to rosbags' serializer.

    Parameters
    ----------
    t_ns : (n,) int64 header stamps.
    frame_id : ``header.frame_id`` of every message.
    values : (n, k) float64 (WrenchStamped: force xyz, torque xyz; PoseStamped: position xyz,
        quaternion xyzw).

    Returns
    -------
    (n, size) uint8, one serialized message per row.

    Raises
    ------
    InputError
        If a stamp does not fit ``builtin_interfaces/msg/Time`` or the shapes disagree.
    """
    stamps = np.asarray(t_ns, dtype=np.int64).reshape(-1)
    floats = np.asarray(values, dtype=np.float64)
    if floats.ndim != 2 or floats.shape[0] != stamps.size:
        raise InputError(f"values must be ({stamps.size}, k), got {floats.shape}")
    name = frame_id.encode("utf-8") + b"\x00"
    float_at = 4 + ((12 + len(name) + 7) & ~7)
    layout = np.dtype(
        {
            "names": ["encap", "sec", "nanosec", "str_len", "name", "values"],
            "formats": ["<u4", "<i4", "<u4", "<u4", f"S{len(name)}", ("<f8", (floats.shape[1],))],
            "offsets": [0, 4, 8, 12, 16, float_at],
            "itemsize": float_at + 8 * floats.shape[1],
        }
    )
    sec, nanosec = np.divmod(stamps, _NS)
    if stamps.size and (sec.min() < -(2**31) or sec.max() >= 2**31):
        raise InputError("a stamp does not fit builtin_interfaces/msg/Time (int32 seconds)")
    records = np.zeros(stamps.size, dtype=layout)
    records["encap"] = 0x100  # bytes 00 01 00 00: CDR little-endian
    records["sec"], records["nanosec"], records["str_len"] = sec, nanosec, len(name)
    records["name"] = name
    records["values"] = floats
    return records.view(np.uint8).reshape(stamps.size, layout.itemsize)


def _transforms(raw: bytes, count: int | None) -> list[TransformSample] | None:
    """``count`` transforms after a ``uint32`` count (None: the count is read first, a TFMessage), or one bare
    TransformStamped (``count`` 1 without a count field); None where the bytes do not fit the layout."""
    if len(raw) < 8 or raw[0] != 0 or raw[1] != 1:
        return None
    body = memoryview(raw)[4:]
    size = len(body)

    def string(at: int) -> tuple[str, int] | None:
        at = (at + 3) & ~3
        if at + 4 > size:
            return None
        (length,) = struct.unpack_from("<I", body, at)
        end = at + 4 + length
        if length < 1 or end > size or body[end - 1] != 0:
            return None
        return bytes(body[at + 4 : end - 1]).decode("utf-8", errors="replace"), end

    at = 0
    if count is None:
        (count,) = struct.unpack_from("<I", body, 0)
        at = 4
    samples = []
    for _ in range(count):
        if at + 8 > size:
            return None
        sec, nanosec = struct.unpack_from("<iI", body, at)
        parent = string(at + 8)
        if parent is None:
            return None
        child = string(parent[1])
        if child is None:
            return None
        at = (child[1] + 7) & ~7
        if at + 56 > size:
            return None
        values = np.frombuffer(body, dtype="<f8", count=7, offset=at).astype(np.float64)
        at += 56
        samples.append(TransformSample(int(sec) * int(_NS) + int(nanosec), parent[0], child[0], values[:3], values[3:]))
    return samples


def decode_tf_message(raw: bytes) -> list[TransformSample] | None:
    """A little-endian CDR ``tf2_msgs/msg/TFMessage`` read without a type store, or None where the bytes do not
    fit its layout (decode those with rosbags'; its type store costs `bsp identify` 0.08 s to build).

    Layout after the 4-byte encapsulation header (alignment counted from its end): ``uint32`` count, then per
    transform ``int32 sec, uint32 nanosec``, ``frame_id`` and ``child_frame_id`` (``uint32`` length, bytes with
    their NUL, each length 4-aligned), the translation (3 float64) and rotation (4 float64) 8-aligned.
    """
    return _transforms(raw, None)


def decode_transform_stamped(raw: bytes) -> TransformSample | None:
    """A little-endian CDR ``geometry_msgs/msg/TransformStamped`` (one transform of :func:`decode_tf_message`'s
    layout, without the count), or None where the bytes do not fit it."""
    samples = _transforms(raw, 1)
    return samples[0] if samples else None
