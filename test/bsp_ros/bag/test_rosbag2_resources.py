"""rosbag2's own test bags (test/data/rosbag2, Apache-2.0): read as mcap reads them, or refused as documented."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from mcap.reader import NonSeekingReader
from test_mcap_conformance import _AllSink

from bsp_ros.bag import MissingTopicError, read_session
from bsp_ros.bag.mcap_scan import scan_mcap
from bsp_ros.cli import main
from bsp_ros.live.replay import PlayReport, _plan, bag_files

DATA = Path(__file__).resolve().parents[2] / "data" / "rosbag2"
CDR_TEST = DATA / "cdr_test"
COMPRESSED = DATA / "compressed_bag"


def _listed_counts(bag: Path) -> dict[str, int]:
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    return {t["topic_metadata"]["name"]: t["message_count"] for t in info["topics_with_message_count"]}


def test_rosbag2s_mcap_is_read_as_mcap_reads_it() -> None:
    (file,) = CDR_TEST.glob("*.mcap")
    sink = _AllSink()
    scan = scan_mcap(file, sink)
    with file.open("rb") as stream:
        records = NonSeekingReader(stream).iter_messages(log_time_order=False)
        truth = [(c.topic, m.log_time, bytes(m.data)) for _, c, m in records]
    assert not scan.damage and scan.messages_seen == len(truth)
    for topic in {t for t, _, _ in truth}:
        assert [m for m in sink.messages if m[0] == topic] == [m for m in truth if m[0] == topic]
    listed = _listed_counts(CDR_TEST)
    assert listed == {"/array_topic": 4, "/test_topic": 3}
    assert scan.summary_counts == listed
    files, meta = bag_files(CDR_TEST)
    plans = _plan(files, meta, None, PlayReport(path=str(CDR_TEST)))
    assert {p.topic: p.expected for p in plans} == listed
    # Metadata version 7 writes the QoS enums as numbers: durability 1 is transient-local (latched).
    assert "durability: 1" in (CDR_TEST / "metadata.yaml").read_text()
    assert {p.topic for p in plans if p.latched} == set(listed)


def test_rosbag2s_mcap_without_session_topics_names_what_it_holds(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(MissingTopicError) as error:
        read_session(CDR_TEST)
    assert set(error.value.present) == {"/array_topic", "/test_topic"}
    assert main(["identify", str(CDR_TEST)]) == 13
    err = capsys.readouterr().err
    assert "/array_topic [test_msgs/msg/Arrays]" in err and "Traceback" not in err


def test_rosbag2s_file_compressed_bag_is_unsupported(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """rosbag2 writes ``compression_mode: FILE`` (upper case) and ``.db3.zstd`` files."""
    assert "compression_mode: FILE" in (COMPRESSED / "metadata.yaml").read_text()
    assert main(["identify", str(COMPRESSED)]) == 16
    assert main(["tare", str(COMPRESSED), "--out", str(tmp_path / "t.yaml")]) == 16
    assert main(["play", str(COMPRESSED), "--wait-subscribers", "0"]) == 4
    (file,) = COMPRESSED.glob("*.zstd")
    assert main(["identify", str(file)]) == 16
    err = capsys.readouterr().err
    assert err.count("error:") == 4 and "Traceback" not in err
