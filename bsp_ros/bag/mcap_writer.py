"""The MCAP writer every bsp_ros bag is written with: uncompressed chunks, CRC-checked, the ros2 profile."""

from __future__ import annotations

from typing import TYPE_CHECKING, BinaryIO

from bsp_ros import __version__

if TYPE_CHECKING:
    from mcap.writer import Writer

__all__ = ["started_mcap_writer"]


def started_mcap_writer(stream: BinaryIO, chunk_bytes: int, writer_name: str = "") -> Writer:
    """An MCAP writer on ``stream``, started: chunks of ``chunk_bytes`` (bytes), uncompressed, every chunk's and
    record's CRC written, the ``ros2`` profile, the library named ``bsp_ros <version> [writer_name] (mcap python)``.
    The mcap package is imported here, not at the module's import: commands that never write a bag start faster."""
    from mcap.writer import CompressionType, Writer

    writer = Writer(
        stream,
        chunk_size=chunk_bytes,
        compression=CompressionType.NONE,
        enable_crcs=True,
        enable_data_crcs=True,
    )
    name = f" {writer_name}" if writer_name else ""
    writer.start(profile="ros2", library=f"bsp_ros {__version__}{name} (mcap python)")
    return writer
