"""The MCAP conformance files (foxglove/mcap): every one read as mcap's own reader reads it, every loss counted."""

from __future__ import annotations

import hashlib
import struct
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import NonSeekingReader
from mcap_conformance import Variant, build, conformance_sha256, variants

from bsp_ros.bag.mcap_scan import ChannelInfo, ScanResult, scan_mcap
from bsp_ros.cli import main

VARIANTS = list(variants())
WITH_MESSAGES = [v for v in VARIANTS if v.messages]
CHUNKED = [v for v in WITH_MESSAGES if "ch" in v.features]


class _AllSink:
    """Takes every channel's messages: (topic, log time, payload) in the order fed."""

    def __init__(self) -> None:
        self.messages: list[tuple[str, int, bytes]] = []

    def wants(self, channel: ChannelInfo) -> bool:
        return True

    def feed(
        self, channel: ChannelInfo, buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
    ) -> None:
        for offset, length, log in zip(offsets.tolist(), lengths.tolist(), log_ns.tolist(), strict=True):
            self.messages.append((channel.topic, int(log), buf[offset : offset + length].tobytes()))


def _write(variant: Variant, directory: Path) -> Path:
    path = directory / f"{variant.name}.mcap"
    path.write_bytes(build(variant))
    return path


def _mcap_truth(path: Path) -> tuple[list[tuple[str, int, bytes]], dict[str, tuple[str, str]]]:
    """Messages (topic, log time, payload) in file order and channels (topic -> schema name, encoding), as
    mcap's streaming reader sees them."""
    with path.open("rb") as stream:
        messages = []
        channels = {}
        for schema, channel, message in NonSeekingReader(stream).iter_messages(log_time_order=False):
            messages.append((channel.topic, message.log_time, bytes(message.data)))
            channels[channel.topic] = (schema.name if schema is not None else "", channel.message_encoding)
    return messages, channels


def test_the_rebuilt_files_are_the_upstream_conformance_files() -> None:
    table = conformance_sha256()
    assert {v.name for v in VARIANTS} == set(table)  # every upstream file, nothing else
    mismatched = [v.name for v in VARIANTS if hashlib.sha256(build(v)).hexdigest() != table[v.name]]
    assert mismatched == []


@pytest.mark.parametrize("variant", VARIANTS, ids=lambda v: v.name)
def test_every_conformance_file_is_read_as_mcap_reads_it(variant: Variant, tmp_path: Path) -> None:
    path = _write(variant, tmp_path)
    sink = _AllSink()
    scan = scan_mcap(path, sink)
    messages, channels = _mcap_truth(path)
    assert not scan.damage and scan.crc_errors == 0 and not scan.truncated
    assert sink.messages == messages  # one channel: file order, payloads byte for byte
    assert scan.messages_seen == len(variant.messages) and scan.orphans == 0
    assert {c.topic: (c.msgtype, c.encoding) for c in scan.channels.values()} == channels
    if "st" in variant.features:
        # With or without the channels repeated in the summary, the counts resolve to topics.
        assert scan.summary_counts == dict(Counter(topic for topic, _, _ in messages))
    else:
        assert scan.summary_counts is None


def _corrupt_chunk(path: Path) -> None:
    """Flip the last byte of the (single) chunk's records, so its CRC fails."""
    data = bytearray(path.read_bytes())
    pos = 8
    while pos < len(data):
        opcode, length = struct.unpack_from("<BQ", data, pos)
        if opcode == 0x06:  # Chunk
            data[pos + 9 + length - 1] ^= 0xFF
            path.write_bytes(bytes(data))
            return
        pos += 9 + length
    raise AssertionError("no chunk")


@pytest.mark.parametrize("variant", CHUNKED, ids=lambda v: v.name)
def test_a_damaged_chunk_is_counted_or_its_loss_said_unknown(variant: Variant, tmp_path: Path) -> None:
    path = _write(variant, tmp_path)
    _corrupt_chunk(path)
    scan: ScanResult = scan_mcap(path, _AllSink())
    n = len(variant.messages)
    assert scan.crc_errors == 1 and scan.messages_seen == 0
    if "mx" in variant.features:
        # The message indexes after the chunk count its messages (named by topic where a Channel survives).
        assert sum(scan.lost_in_bad_chunks.values()) == n
        assert set(scan.lost_in_bad_chunks) == {"example" if "rch" in variant.features else "<channel 1>"}
    else:
        # No message index: a chunk index without them lists no channel either, so any topic may have lost.
        assert scan.lost_in_bad_chunks == {} and scan.uncounted_loss_any
    if "st" in variant.features:
        assert sum((scan.summary_counts or {}).values()) == n  # expected minus read: all n lost


def _exit_code(args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = main(args)
    return code, capsys.readouterr().err


@pytest.mark.parametrize("command", ["identify", "tare"])
def test_commands_refuse_each_conformance_file_with_its_documented_code(
    command: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """No ROS topic in any of them: 12 (empty) for the files without a message, 13 (missing topic, naming the
    topic present) for the others; never 12 for a file that holds messages."""
    for variant in VARIANTS:
        path = _write(variant, tmp_path)
        args = [command, str(path)] + (["--out", str(tmp_path / "tare.yaml")] if command == "tare" else [])
        code, err = _exit_code(args, capsys)
        if variant.messages:
            assert code == 13, (variant.name, err)
            assert "example" in err, variant.name
        else:
            assert code == 12, (variant.name, err)
        assert "Traceback" not in err


def test_identify_and_tare_tell_a_lost_topic_from_a_missing_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Each file's only chunk damaged. With every channel repeated in the summary, the wrench topic is known
    to be absent: missing (13). Otherwise the lost chunk held channels unknown, the topic may have been
    among them: corrupt (15), naming the CRC failure. Never empty (12)."""
    for variant, command in [(v, c) for v in CHUNKED for c in ("identify", "tare")]:
        path = _write(variant, tmp_path)
        _corrupt_chunk(path)
        args = [command, str(path)] + (["--out", str(tmp_path / "tare.yaml")] if command == "tare" else [])
        code, err = _exit_code(args, capsys)
        if "rch" in variant.features:
            assert code == 13 and "example" in err, (variant.name, err)
        else:
            assert code == 15 and "fails its CRC" in err, (variant.name, err)
