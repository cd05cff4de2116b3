"""Compressed bag content: rosbag2 per-message compression undone in bulk, compressed files recognised by magic."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.bag.errors import UnsupportedBagError

#: Frame magics of the compressors rosbag2 (zstd) and MCAP (zstd, lz4) use.
ZSTD_MAGIC = b"\x28\xb5\x2f\xfd"
LZ4_FRAME_MAGIC = b"\x04\x22\x4d\x18"
#: rosbag2 ``compression_format`` values whose per-message compression this reader undoes.
MESSAGE_FORMATS = ("zstd", "lz4")


def normalized(value: object) -> str:
    """A metadata word (``compression_mode``, ``storage_identifier``...) compared case-insensitively.

    rosbag2 writes ``FILE``/``MESSAGE`` (and ``""`` or ``NONE`` for none), rosbags ``file``/``message``.
    """
    text = str(value or "").strip().lower()
    return "" if text == "none" else text


def check_message_format(compression_format: str, where: str) -> str:
    """``compression_format`` of a message-compressed bag, lower case, if this reader undoes it.

    Raises
    ------
    UnsupportedBagError
        For any other format (naming it and ``where``).
    """
    fmt = normalized(compression_format)
    if fmt not in MESSAGE_FORMATS:
        raise UnsupportedBagError(
            f"{where} compresses each message with {compression_format!r}; only "
            f"{' and '.join(MESSAGE_FORMATS)} are read (`ros2 bag convert` can write it uncompressed)"
        )
    return fmt


def _decompress_one(payload: bytes) -> bytes:
    if payload.startswith(ZSTD_MAGIC):
        import zstandard

        # A frame without its content size in the header needs the streaming decompressor, which returns what
        # it could of a cut frame without complaint: its ``eof`` says whether the frame was whole.
        stream = zstandard.ZstdDecompressor().decompressobj()
        data = bytes(stream.decompress(payload))
        if not stream.eof:
            raise ValueError("the zstd frame is cut short")
        return data
    import lz4.frame

    return bytes(lz4.frame.decompress(payload))


@dataclass
class Decompressed:
    """Messages after undoing per-message compression.

    Attributes
    ----------
    buf : (B,) uint8 bytes holding the messages (the input buffer when nothing was compressed).
    offsets, lengths : (n,) int64 where each kept message starts and its length.
    log_ns : (n,) int64 log times of the kept messages.
    decompressed : messages that were compressed frames and were expanded.
    failed : compressed frames that did not decompress (dropped; ``first_error`` says why).
    """

    buf: np.ndarray
    offsets: np.ndarray
    lengths: np.ndarray
    log_ns: np.ndarray
    decompressed: int = 0
    failed: int = 0
    first_error: str = ""


def decompress_cdr_messages(
    buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
) -> Decompressed:
    """Expand the CDR messages that are stored as zstd or lz4 frames (rosbag2 ``compression_mode: message``).

    A serialized CDR message starts with its encapsulation header, whose first byte is always 0; a payload
    starting with a zstd or lz4 frame magic cannot be CDR, so it is decompressed whatever the metadata says.

    Parameters
    ----------
    buf : (B,) uint8 buffer; offsets, lengths, log_ns : (n,) int64 per message.

    Returns
    -------
    Decompressed
    """
    n = offsets.size
    if n == 0:
        return Decompressed(buf, offsets, lengths, log_ns)
    first = np.zeros(n, dtype=np.uint8)
    nonempty = lengths > 0
    first[nonempty] = buf[offsets[nonempty]]
    if not first.any():  # plain CDR throughout: nothing to do
        return Decompressed(buf, offsets, lengths, log_ns)
    pieces: list[bytes] = []
    keep = np.ones(n, dtype=bool)
    out = Decompressed(buf, offsets, lengths, log_ns)
    for i, (offset, length) in enumerate(zip(offsets.tolist(), lengths.tolist(), strict=True)):
        payload = buf[offset : offset + length].tobytes()
        if first[i] and payload[:4] in (ZSTD_MAGIC, LZ4_FRAME_MAGIC):
            try:
                payload = _decompress_one(payload)
                out.decompressed += 1
            except Exception as error:  # any decompressor failure: this message is damaged
                keep[i] = False
                out.failed += 1
                out.first_error = out.first_error or f"{error.__class__.__name__}: {error}"
                continue
        pieces.append(payload)
    sizes = np.array([len(p) for p in pieces], dtype=np.int64)
    out.buf = np.frombuffer(b"".join(pieces), dtype=np.uint8)
    out.offsets = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64) if sizes.size else sizes
    out.lengths = sizes
    out.log_ns = log_ns[keep]
    return out


def sniff_compressed_file(head: bytes) -> str | None:
    """The kind of a whole-file compressed or foreign bag file from its first bytes, or None.

    Returns a phrase such as ``"a zstd-compressed file"``, ``"a rosbag2 sqlite3 file"``, ``"a ROS 1 bag"``.
    """
    if head.startswith(ZSTD_MAGIC):
        return "a zstd-compressed file (rosbag2 file compression?): decompress it first (`ros2 bag decompress`)"
    if head.startswith(LZ4_FRAME_MAGIC):
        return "an lz4-compressed file: decompress it first"
    if head.startswith(b"SQLite format 3\x00"):
        return (
            "a rosbag2 sqlite3 (.db3) file; only mcap storage is read "
            "(convert it with `ros2 bag convert` or `rosbags-convert --dst-storage mcap`)"
        )
    if head.startswith(b"#ROSBAG V"):
        return "a ROS 1 bag; only rosbag2 mcap storage is read (convert it with `rosbags-convert`)"
    return None
