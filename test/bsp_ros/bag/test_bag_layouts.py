"""Layouts real tools write (mcap writer options, rosbags' storage and compression modes): counted exactly,
read exactly, or refused with the documented exit code by every command."""

from __future__ import annotations

import json
import queue
import shutil
import threading
from pathlib import Path

import numpy as np
import pytest
from bag_layouts import damage_chunk, edit_metadata, raw_messages, write_mcap, write_rosbags
from mcap.writer import CompressionType, IndexType
from rosbags.rosbag2 import CompressionMode, StoragePlugin

from bsp_ros.bag import read_session, write_session_bag
from bsp_ros.bag.tare_reader import read_tare_bag
from bsp_ros.cli import main
from bsp_ros.core.simulation import SimulatedSession
from bsp_ros.live.replay import bag_files
from bsp_ros.live.replay.batches import scan_thread
from bsp_ros.live.replay.plan import plan_topics

LIST_ONLY = "the bag lists only"


@pytest.fixture(scope="module")
def source_bag(tmp_path_factory: pytest.TempPathFactory, human_session: SimulatedSession) -> Path:
    """A 20 s session bag as bsp_ros writes it (the messages every layout below rewrites)."""
    out = tmp_path_factory.mktemp("source") / "session"
    return write_session_bag(out, human_session.session, human_session.truth.to_dict())


def _bsp(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str]:
    code = main(list(argv))
    return code, capsys.readouterr().err


LAYOUTS = [
    pytest.param(repeat, statistics, indexes, id=f"rch={repeat}-st={statistics}-index={indexes.name}")
    for repeat in (False, True)
    for statistics in (True, False)
    for indexes in (IndexType.ALL, IndexType.NONE)
]


@pytest.mark.parametrize(("repeat", "statistics", "indexes"), LAYOUTS)
def test_an_intact_file_is_counted_per_topic_in_every_summary_layout(
    repeat: bool, statistics: bool, indexes: IndexType, source_bag: Path, tmp_path: Path
) -> None:
    """Statistics without repeated Channel records (rosbag2 ``noRepeatedChannels``) still count per topic."""
    file = write_mcap(
        source_bag, tmp_path / "x.mcap", repeat_channels=repeat, use_statistics=statistics, index_types=indexes
    )
    truth: dict[str, int] = {}
    for topic, _, _, _ in raw_messages(source_bag):
        truth[topic] = truth.get(topic, 0) + 1
    report = read_session(file).report
    assert report.clean and report.lost_messages == 0
    assert not [w for w in report.warnings if LIST_ONLY in w]
    for topic, rep in report.topics.items():
        assert rep.read == truth[topic]
        assert rep.expected == (truth[topic] if statistics else None), topic


@pytest.mark.parametrize(("repeat", "statistics", "indexes"), LAYOUTS)
def test_a_damaged_chunk_reports_its_true_loss_or_says_it_is_unknown(
    repeat: bool, statistics: bool, indexes: IndexType, source_bag: Path, tmp_path: Path
) -> None:
    file = write_mcap(
        source_bag,
        tmp_path / "x.mcap",
        repeat_channels=repeat,
        use_statistics=statistics,
        index_types=indexes,
        chunk_size=64 * 1024,
        compression=CompressionType.ZSTD,
    )
    held = damage_chunk(file, 2)
    assert sum(held.values()) > 100
    report = read_session(file).report
    assert report.crc_errors == 1
    counted = statistics or indexes != IndexType.NONE  # Statistics, or the message indexes after the chunk
    for topic, rep in report.topics.items():
        assert rep.lost == (held.get(topic, 0) if counted else None), topic
    assert report.lost_messages == (sum(held.values()) if counted else None)
    if not counted:
        assert any("number of lost messages is unknown" in w for w in report.warnings)


def _assert_same_session(got: SimulatedSession, want: SimulatedSession) -> None:
    assert got.session.wrench.t_ns.tobytes() == want.session.wrench.t_ns.tobytes()
    assert got.session.wrench.force_n.tobytes() == want.session.wrench.force_n.tobytes()
    assert got.session.wrench.torque_nm.tobytes() == want.session.wrench.torque_nm.tobytes()
    assert set(got.session.markers) == set(want.session.markers)
    for name, series in want.session.markers.items():
        assert got.session.markers[name].position_m.tobytes() == series.position_m.tobytes()
    np.testing.assert_array_equal(got.session.rotation_world_from_sensor, want.session.rotation_world_from_sensor)


@pytest.mark.parametrize("spelling", ["message", "MESSAGE"])
def test_a_message_compressed_bag_reads_as_the_uncompressed_one(
    spelling: str, source_bag: Path, tmp_path: Path
) -> None:
    """rosbags writes ``compression_mode: message`` (rosbag2 ``MESSAGE``): every payload a zstd frame."""
    bag = write_rosbags(source_bag, tmp_path / "compressed", mode=CompressionMode.MESSAGE)
    edit_metadata(bag, compression_mode=spelling)
    assert all(data[:4] == b"\x28\xb5\x2f\xfd" for *_, data in raw_messages(bag))  # really compressed
    want = read_session(source_bag)
    got = read_session(bag)
    _assert_same_session(got, want)  # type: ignore[arg-type]
    assert got.report.clean and got.report.lost_messages == 0
    assert {t: r.read for t, r in got.report.topics.items()} == {t: r.read for t, r in want.report.topics.items()}
    tare_want, tare_got = read_tare_bag(source_bag), read_tare_bag(bag)
    assert tare_got.force_n.tobytes() == tare_want.force_n.tobytes()


def test_play_publishes_the_decompressed_cdr(source_bag: Path, tmp_path: Path) -> None:
    """What `bsp play` would publish (its scan thread's batches, no DDS needed) is the recorded CDR."""
    bag = write_rosbags(source_bag, tmp_path / "compressed", mode=CompressionMode.MESSAGE)
    files, meta = bag_files(bag)
    plans = plan_topics(files, meta, None, _empty_play_report(bag))
    want = {topic: n for topic, n in _counts(raw_messages(source_bag)).items()}
    assert {p.topic: p.expected for p in plans} == want
    batches: queue.Queue = queue.Queue(maxsize=4)
    thread = scan_thread(files, lambda c: True, batches, threading.Event())
    published: dict[str, list[bytes]] = {}
    while (item := batches.get()) is not None:
        if isinstance(item, BaseException):
            raise item
        if isinstance(item, list):
            for _, topic, data in item:
                published.setdefault(topic, []).append(data)
    thread.join()
    recorded: dict[str, list[bytes]] = {}
    for topic, _, _, data in raw_messages(source_bag):
        recorded.setdefault(topic, []).append(data)
    assert {t: sorted(v) for t, v in published.items()} == {t: sorted(v) for t, v in recorded.items()}


def _counts(messages: list[tuple[str, str, int, bytes]]) -> dict[str, int]:
    counts: dict[str, int] = {}
    for topic, *_ in messages:
        counts[topic] = counts.get(topic, 0) + 1
    return counts


def _empty_play_report(bag: Path):  # type: ignore[no-untyped-def]
    from bsp_ros.live.replay import PlayReport

    return PlayReport(path=str(bag))


def test_identify_reads_a_message_compressed_bag(
    source_bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = write_rosbags(source_bag, tmp_path / "compressed", mode=CompressionMode.MESSAGE)
    code, err = _bsp(capsys, "identify", str(bag), "--json", str(tmp_path / "e.json"))
    assert code in (0, 1), err
    document = json.loads((tmp_path / "e.json").read_text())
    assert document["bag"]["messages"]["/ft_sensor/wrench"] == _counts(raw_messages(source_bag))["/ft_sensor/wrench"]
    assert document["bag"]["lost_messages"] == 0


def _refusals(bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> dict[str, tuple[int, str]]:
    """Exit code and stderr of every command that reads a bag (`sessions add` takes a file for a bag only by
    its suffix, .mcap/.db3/.bag, else for a result JSON)."""
    codes = {
        "identify": _bsp(capsys, "identify", str(bag)),
        "tare": _bsp(capsys, "tare", str(bag), "--out", str(tmp_path / "t.yaml")),
        "play": _bsp(capsys, "play", str(bag), "--wait-subscribers", "0"),
    }
    if bag.is_dir() or bag.suffix in (".mcap", ".db3", ".bag"):
        store = str(tmp_path / "s.sqlite")
        codes["sessions add"] = _bsp(capsys, "sessions", "add", str(bag), "--subject", "S1", "--store", store)
    return codes


def _assert_unsupported(bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], words: str) -> None:
    for command, (code, err) in _refusals(bag, tmp_path, capsys).items():
        # README: 16 unsupported storage/compression for identify and tare, 4 any bag failure for the others.
        assert code == (16 if command in ("identify", "tare") else 4), (command, err)
        assert words in err and "Traceback" not in err, (command, err)
        assert len(err.strip().splitlines()) == 1, (command, err)


@pytest.mark.parametrize("spelling", ["file", "FILE"])
def test_a_file_compressed_bag_is_refused_as_unsupported(
    spelling: str, source_bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """rosbag2 writes ``compression_mode: FILE`` (its own test bag compressed_bag does), rosbags ``file``."""
    bag = write_rosbags(source_bag, tmp_path / "filecompressed", mode=CompressionMode.FILE)
    edit_metadata(bag, compression_mode=spelling)
    _assert_unsupported(bag, tmp_path, capsys, "decompress it first")
    (compressed,) = bag.glob("*.mcap.zstd")
    _assert_unsupported(compressed, tmp_path, capsys, "zstd-compressed")  # the file alone
    (bag / "metadata.yaml").unlink()
    _assert_unsupported(bag, tmp_path, capsys, "file compression")  # the folder without its metadata


def test_an_unknown_message_compression_format_is_refused(
    source_bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = write_rosbags(source_bag, tmp_path / "compressed", mode=CompressionMode.MESSAGE)
    edit_metadata(bag, compression_format="bz2")
    _assert_unsupported(bag, tmp_path, capsys, "'bz2'")


def test_a_sqlite3_bag_is_refused_as_unsupported_storage_however_given(
    source_bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = write_rosbags(source_bag, tmp_path / "sqlite", storage=StoragePlugin.SQLITE3)
    _assert_unsupported(bag, tmp_path, capsys, "sqlite3")
    (db3,) = bag.glob("*.db3")
    _assert_unsupported(db3, tmp_path, capsys, "sqlite3")  # the .db3 file itself
    alone = tmp_path / "db3_only"
    alone.mkdir()
    shutil.copy(db3, alone / db3.name)
    _assert_unsupported(alone, tmp_path, capsys, "sqlite3")  # a folder without metadata.yaml
