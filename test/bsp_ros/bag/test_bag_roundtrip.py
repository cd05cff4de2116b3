"""Bags written by write_session_bag: read back bit-exact, by us, by rosbags and by mcap_ros2 alike."""

from __future__ import annotations

import dataclasses
import itertools
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from bsp_ros.bag import BagWriteError, read_session, write_session_bag
from bsp_ros.bag.writer import TRUTH_FILE
from bsp_ros.cli import main as bsp_main
from bsp_ros.core.simulation import SimulatedSession
from bsp_ros.core.streams import Session, WrenchSeries

TOPIC = {
    "shoulder": "/mocap/shoulder",
    "elbow": "/mocap/elbow",
    "wrist": "/mocap/wrist",
    "hand": "/mocap/hand",
}


def assert_same_bits(a: np.ndarray, b: np.ndarray) -> None:
    assert a.shape == b.shape and a.dtype == b.dtype
    assert np.ascontiguousarray(a).tobytes() == np.ascontiguousarray(b).tobytes()


def assert_sessions_equal(got: Session, want: Session) -> None:
    assert got.wrench.frame_id == want.wrench.frame_id
    assert_same_bits(got.wrench.t_ns, want.wrench.t_ns.astype(np.int64))
    assert_same_bits(got.wrench.force_n, want.wrench.force_n.astype(np.float64))
    assert_same_bits(got.wrench.torque_nm, want.wrench.torque_nm.astype(np.float64))
    assert sorted(got.markers) == sorted(want.markers)
    for name, series in want.markers.items():
        assert_same_bits(got.markers[name].t_ns, series.t_ns.astype(np.int64))
        assert_same_bits(got.markers[name].position_m, series.position_m.astype(np.float64))
    np.testing.assert_allclose(got.rotation_world_from_sensor, want.rotation_world_from_sensor, atol=1e-14)


def test_read_back_equals_written(human_session: SimulatedSession, write_bag: Callable[..., Path]) -> None:
    bag = write_bag(human_session)
    result = read_session(bag)
    assert_sessions_equal(result.session, human_session.session)
    report = result.report
    assert report.clean, report.warnings
    assert report.n_segments == 3 and result.session.n_segments == 3
    assert report.crc_errors == 0 and report.chunks_without_crc == 0 and report.chunks_read > 1
    assert report.rotation_source == "tf" and report.warnings == []
    for name, series in human_session.session.markers.items():
        assert report.topics[TOPIC[name]].read == report.topics[TOPIC[name]].expected == series.t_ns.size
    # Receive times: the stamps plus a small positive delay.
    delay = result.receive_ns["wrench"] - human_session.session.wrench.t_ns
    assert (delay > 0).all() and (delay < 5_000_000).all()
    assert json.loads((bag / TRUTH_FILE).read_text()) == json.loads(json.dumps(human_session.truth.to_dict()))


def test_single_mcap_file_reads_alone(human_session: SimulatedSession, write_bag: Callable[..., Path]) -> None:
    bag = write_bag(human_session)
    (file,) = bag.glob("*.mcap")
    result = read_session(file)
    assert_sessions_equal(result.session, human_session.session)
    assert result.report.topics["/ft_sensor/wrench"].expected == human_session.session.wrench.t_ns.size


def test_independent_decoder_sees_the_same_messages(
    human_session: SimulatedSession, write_bag: Callable[..., Path]
) -> None:
    bag = write_bag(human_session)
    (file,) = bag.glob("*.mcap")
    stamps: dict[str, list[int]] = {}
    values: dict[str, list[list[float]]] = {}
    frames: dict[str, set[str]] = {}
    with file.open("rb") as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        summary = reader.get_summary()
        assert summary is not None
        assert all(c.compression == "" and c.uncompressed_size < 80 * 1024 for c in summary.chunk_indexes)
        assert reader.get_header().profile == "ros2"
        for _, channel, message, msg in reader.iter_decoded_messages(log_time_order=False):
            if channel.topic == "/tf_static":
                (tf,) = msg.transforms
                assert (tf.header.frame_id, tf.child_frame_id) == ("world", "ft_sensor")
                continue
            stamps.setdefault(channel.topic, []).append(msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec)
            frames.setdefault(channel.topic, set()).add(msg.header.frame_id)
            if channel.topic == "/ft_sensor/wrench":
                f, t = msg.wrench.force, msg.wrench.torque
                values.setdefault(channel.topic, []).append([f.x, f.y, f.z, t.x, t.y, t.z])
            else:
                p = msg.pose.position
                values.setdefault(channel.topic, []).append([p.x, p.y, p.z])
            assert message.log_time > message.publish_time
    w = human_session.session.wrench
    assert frames["/ft_sensor/wrench"] == {"ft_sensor"}
    np.testing.assert_array_equal(stamps["/ft_sensor/wrench"], w.t_ns)
    assert_same_bits(np.array(values["/ft_sensor/wrench"]), np.hstack([w.force_n, w.torque_nm]))
    for name, series in human_session.session.markers.items():
        assert frames[TOPIC[name]] == {"world"}
        np.testing.assert_array_equal(stamps[TOPIC[name]], series.t_ns)
        assert_same_bits(np.array(values[TOPIC[name]]), series.position_m)


def test_rosbags_reads_the_bag(human_session: SimulatedSession, write_bag: Callable[..., Path]) -> None:
    bag = write_bag(human_session)
    counts: dict[str, int] = {}
    with AnyReader([bag], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        durability = {c.topic: c.ext.offered_qos_profiles[0].durability.name for c in reader.connections}
        for connection, _, raw in reader.messages():
            reader.deserialize(raw, connection.msgtype)
            counts[connection.topic] = counts.get(connection.topic, 0) + 1
    assert durability["/tf_static"] == "TRANSIENT_LOCAL" and durability["/ft_sensor/wrench"] == "VOLATILE"
    assert counts["/ft_sensor/wrench"] == human_session.session.wrench.t_ns.size
    assert counts["/tf_static"] == 1


def test_metadata_yaml_has_what_jazzy_needs(human_session: SimulatedSession, write_bag: Callable[..., Path]) -> None:
    bag = write_bag(human_session)
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["version"] == 9 and info["storage_identifier"] == "mcap"
    (file,) = bag.glob("*.mcap")
    assert info["relative_file_paths"] == [file.name] and info["files"][0]["path"] == file.name
    assert info["duration"]["nanoseconds"] > 19 * 10**9
    assert info["starting_time"]["nanoseconds_since_epoch"] > 0
    topics = {t["topic_metadata"]["name"]: t for t in info["topics_with_message_count"]}
    assert set(topics) == {"/ft_sensor/wrench", "/tf_static", *TOPIC.values()}
    assert info["message_count"] == sum(t["message_count"] for t in topics.values())
    for entry in topics.values():
        meta = entry["topic_metadata"]
        assert meta["serialization_format"] == "cdr" and meta["type"].count("/msg/") == 1
        assert meta["type_description_hash"].startswith("RIHS01_")
        assert isinstance(meta["offered_qos_profiles"], list) and meta["offered_qos_profiles"]
    assert topics["/tf_static"]["topic_metadata"]["offered_qos_profiles"][0]["durability"] == "transient_local"
    assert topics["/ft_sensor/wrench"]["topic_metadata"]["type"] == "geometry_msgs/msg/WrenchStamped"
    assert topics["/mocap/hand"]["topic_metadata"]["type"] == "geometry_msgs/msg/PoseStamped"
    assert topics["/tf_static"]["topic_metadata"]["type"] == "tf2_msgs/msg/TFMessage"


def test_two_segment_chain_is_inferred(paper_session: SimulatedSession, write_bag: Callable[..., Path]) -> None:
    result = read_session(write_bag(paper_session))
    assert result.report.n_segments == 2 and result.session.n_segments == 2
    assert sorted(result.session.markers) == ["elbow", "hand", "shoulder"]
    assert_sessions_equal(result.session, paper_session.session)


def test_nan_and_disordered_stamps_are_returned_with_a_report(
    human_session: SimulatedSession, write_bag: Callable[..., Path]
) -> None:
    w = human_session.session.wrench
    force = w.force_n.copy()
    force[[3, 50], 1] = np.nan
    torque = w.torque_nm.copy()
    torque[7, 2] = np.inf
    t_ns = w.t_ns.copy()
    t_ns[[10, 11]] = t_ns[[11, 10]]  # swapped: one step backwards
    t_ns[20] = t_ns[19]  # duplicate
    odd = dataclasses.replace(
        human_session,
        session=dataclasses.replace(human_session.session, wrench=WrenchSeries(t_ns, force, torque, w.frame_id)),
    )
    result = read_session(write_bag(odd))
    assert_sessions_equal(result.session, odd.session)
    rep = result.report.topics["/ft_sensor/wrench"]
    assert (rep.non_finite, rep.out_of_order, rep.duplicate_stamps) == (3, 1, 1)
    assert not result.report.clean and result.report.lost_messages == 0
    assert any("non-finite" in w for w in result.report.warnings)


def test_no_transform_warns_or_uses_alias(human_session: SimulatedSession, write_bag: Callable[..., Path]) -> None:
    from bsp_ros.bag import TopicMap

    bag = write_bag(human_session)
    no_tf = TopicMap(tf_static="/not_recorded", tf="/not_recorded_either")
    assumed = read_session(bag, topics=no_tf)
    np.testing.assert_array_equal(assumed.session.rotation_world_from_sensor, np.eye(3))
    assert assumed.report.rotation_source == "assumed"
    assert any("no transform" in w for w in assumed.report.warnings)
    aliased = read_session(bag, topics=no_tf, frame_aliases={"ft_sensor": "world"})
    assert aliased.report.rotation_source == "alias"
    assert not any("no transform" in w for w in aliased.report.warnings)


def test_progress_is_reported(human_session: SimulatedSession, write_bag: Callable[..., Path]) -> None:
    seen: list[tuple[int, int]] = []
    read_session(write_bag(human_session), progress=lambda done, total: seen.append((done, total)))
    assert len(seen) > 2 and seen[-1][0] == seen[-1][1]
    assert all(b[0] >= a[0] for a, b in itertools.pairwise(seen))


def test_writer_refuses_to_overwrite(human_session: SimulatedSession, tmp_path: Path) -> None:
    (tmp_path / "taken").mkdir()
    with pytest.raises(BagWriteError, match="exists"):
        write_session_bag(tmp_path / "taken", human_session.session)


def test_cli_simulate_writes_a_readable_bag(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "session_a"
    assert bsp_main(["simulate", "--out", str(out), "--duration", "5", "--seed", "3", "--dropout", "0.1"]) == 0
    assert (out / TRUTH_FILE).is_file()
    result = read_session(out)
    assert result.report.n_segments == 3 and result.report.lost_messages == 0
    assert bsp_main(["simulate", "--out", str(out)]) == 4
    assert "exists" in capsys.readouterr().err
    paper = tmp_path / "session_b"
    assert (
        bsp_main(
            ["simulate", "--out", str(paper), "--subject", "paper-arm", "--duration", "4", "--stiffness", "0.5", "1.0"]
        )
        == 0
    )
    assert read_session(paper).report.n_segments == 2
    truth = json.loads((paper / TRUTH_FILE).read_text())
    assert "0.5" in json.dumps(truth)
    assert bsp_main(["simulate", "--out", str(tmp_path / "c"), "--subject", "paper-arm", "--height", "1.8"]) == 2
    assert bsp_main(["simulate", "--out", str(tmp_path / "d"), "--stiffness", "1.0"]) == 2
    assert not (tmp_path / "c").exists() and not (tmp_path / "d").exists()
