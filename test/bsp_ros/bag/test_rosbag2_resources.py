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
from bsp_ros.live.replay import PlayReport, bag_files
from bsp_ros.live.replay.plan import plan_topics

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
    plans = plan_topics(files, meta, None, PlayReport(path=str(CDR_TEST)))
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


SERVICE_EVENTS = DATA / "bag_with_topics_and_service_events"
WRONG_RMW = DATA / "wrong_rmw_test"
SQLITE3 = DATA / "sqlite3_cdr_test"


@pytest.mark.parametrize("bag", [SERVICE_EVENTS, WRONG_RMW], ids=lambda p: p.name)
def test_rosbag2s_other_mcap_bags_are_counted_as_their_metadata_lists(bag: Path) -> None:
    # Metadata version 8 with type hashes, service-event topics and a topic without messages; version 6 with a
    # serialization format rosbag2 does not know ("wrong_format"): the counts are the file's either way.
    (file,) = bag.glob("*.mcap")
    scan = scan_mcap(file, _AllSink())
    listed = _listed_counts(bag)
    assert not scan.damage and scan.messages_seen == sum(listed.values())
    assert {t: n for t, n in scan.summary_counts.items() if n} == {t: n for t, n in listed.items() if n}
    files, meta = bag_files(bag)
    report = PlayReport(path=str(bag))
    plans = plan_topics(files, meta, None, report)
    if bag == WRONG_RMW:  # nothing it could publish as CDR
        assert not plans and set(report.skipped) == set(listed)
    else:
        assert {p.topic: p.expected for p in plans if p.expected} == {t: n for t, n in listed.items() if n}


def test_a_bag_with_nothing_to_play_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    # Before: "published 0 messages", exit 0, as if the replay had worked.
    assert main(["play", str(WRONG_RMW), "--wait-subscribers", "0"]) == 4
    err = capsys.readouterr().err
    assert "nothing to play, every topic is skipped" in err and "encoded as 'wrong_format', not cdr" in err


def test_a_bag_of_service_events_names_them_and_refuses_them_as_a_wrench(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["identify", str(SERVICE_EVENTS)]) == 13
    assert "/test_service1/_service_event [test_msgs/srv/BasicTypes_Event]" in capsys.readouterr().err
    assert main(["identify", str(SERVICE_EVENTS), "--wrench-topic", "/test_service1/_service_event"]) == 14
    err = capsys.readouterr().err
    assert "carries test_msgs/srv/BasicTypes_Event, expected geometry_msgs/msg/WrenchStamped" in err
    assert main(["identify", str(WRONG_RMW), "--wrench-topic", "/test_topic"]) == 14
    assert "Traceback" not in capsys.readouterr().err


def test_rosbag2s_sqlite3_bag_is_unsupported_as_a_folder_and_as_a_file(capsys: pytest.CaptureFixture[str]) -> None:
    assert "storage_identifier: sqlite3" in (SQLITE3 / "metadata.yaml").read_text()
    assert main(["identify", str(SQLITE3)]) == 16
    assert main(["identify", str(SQLITE3 / "cdr_test_0.db3")]) == 16
    err = capsys.readouterr().err
    assert "uses storage 'sqlite3'" in err and "is a rosbag2 sqlite3 (.db3) file" in err
    assert err.count("rosbags-convert --dst-storage mcap") == 2 and "Traceback" not in err
