"""Damaged, empty and wrong bags: the intact part is returned, the loss reported, the errors distinct."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import Writer
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as RosbagsWriter
from rosbags.typesys import Stores, get_typestore

from bsp_ros.bag import (
    BagCorruptError,
    BagNotFoundError,
    EmptyBagError,
    MessageTypeError,
    MissingTopicError,
    NotABagError,
    TopicMap,
    read_session,
    write_session_bag,
)
from bsp_ros.core.simulation import SimulatedSession
from bsp_ros.core.streams import MarkerSeries, Session, WrenchSeries
from bsp_ros.errors import BagError
from msg_adapters import PoseSample, WrenchSample, build_pose_stamped, build_wrench_stamped

TYPESTORE = get_typestore(Stores.ROS2_JAZZY)
MARKER_TOPICS = {"shoulder": "/mocap/shoulder", "elbow": "/mocap/elbow", "wrist": "/mocap/wrist", "hand": "/mocap/hand"}


def mcap_of(bag: Path) -> Path:
    (file,) = bag.glob("*.mcap")
    return file


def assert_rows_from(got_t: np.ndarray, got_v: np.ndarray, want_t: np.ndarray, want_v: np.ndarray) -> None:
    """Every returned row is an original row, bit for bit (nothing altered)."""
    index = {int(t): i for i, t in enumerate(want_t)}
    rows = np.array([index[int(t)] for t in got_t], dtype=np.int64)
    assert np.ascontiguousarray(got_v).tobytes() == np.ascontiguousarray(want_v[rows]).tobytes()


@pytest.mark.parametrize("fraction", [0.15, 0.5, 0.83, 0.97])
def test_truncated_bag_reads_the_intact_prefix(
    fraction: float, human_session: SimulatedSession, write_bag: Callable[..., Path]
) -> None:
    bag = write_bag(human_session)
    file = mcap_of(bag)
    data = file.read_bytes()
    file.write_bytes(data[: int(len(data) * fraction)])
    result = read_session(bag)
    report = result.report
    assert report.truncated and report.damaged and not report.clean
    assert report.lost_messages is not None and report.lost_messages > 0
    assert any("truncated" in line for line in report.damage)
    w_want, w_got = human_session.session.wrench, result.session.wrench
    n = w_got.t_ns.size
    assert 0 < n < w_want.t_ns.size
    np.testing.assert_array_equal(w_got.t_ns, w_want.t_ns[:n])  # a prefix, in order
    assert w_got.force_n.tobytes() == w_want.force_n[:n].tobytes()
    for name, series in result.session.markers.items():
        want = human_session.session.markers[name]
        m = series.t_ns.size
        np.testing.assert_array_equal(series.t_ns, want.t_ns[:m])
        assert series.position_m.tobytes() == want.position_m[:m].tobytes()
    for topic, rep in report.topics.items():
        assert rep.expected is not None and rep.lost == rep.expected - rep.read, topic
    assert report.topics["/ft_sensor/wrench"].lost == w_want.t_ns.size - n
    with pytest.raises(BagCorruptError) as error:
        read_session(bag, strict=True)
    assert error.value.code == "corrupt" and error.value.lost_messages == report.lost_messages


def test_truncated_summary_loses_nothing_but_is_reported(
    human_session: SimulatedSession, write_bag: Callable[..., Path]
) -> None:
    bag = write_bag(human_session)
    file = mcap_of(bag)
    data = file.read_bytes()
    file.write_bytes(data[:-50])  # inside the summary section: every chunk is intact
    result = read_session(bag)
    assert result.report.truncated and result.report.lost_messages == 0 and not result.report.clean
    assert result.session.wrench.t_ns.size == human_session.session.wrench.t_ns.size
    with pytest.raises(BagCorruptError):
        read_session(bag, strict=True)


def test_truncated_before_any_marker_is_a_corrupt_bag(
    human_session: SimulatedSession, write_bag: Callable[..., Path]
) -> None:
    bag = write_bag(human_session)
    file = mcap_of(bag)
    file.write_bytes(file.read_bytes()[:400])
    with pytest.raises(BagCorruptError, match="no intact message"):
        read_session(bag)


def test_flipped_byte_is_a_crc_error_not_altered_data(
    human_session: SimulatedSession, write_bag: Callable[..., Path]
) -> None:
    bag = write_bag(human_session)
    file = mcap_of(bag)
    with file.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    chunk = summary.chunk_indexes[len(summary.chunk_indexes) // 2]
    data = bytearray(file.read_bytes())
    data_start = chunk.chunk_start_offset + 9 + 40 + len(chunk.compression)
    where = data_start + chunk.uncompressed_size // 2
    data[where] ^= 0x10
    file.write_bytes(bytes(data))

    result = read_session(bag)
    report = result.report
    assert report.crc_errors == 1 and not report.truncated and report.damaged
    assert any("CRC" in line for line in report.damage)
    lost = report.lost_messages
    assert lost is not None and 0 < lost < 1000
    w_want, w_got = human_session.session.wrench, result.session.wrench
    assert w_got.t_ns.size < w_want.t_ns.size
    assert_rows_from(
        w_got.t_ns,
        np.hstack([w_got.force_n, w_got.torque_nm]),
        w_want.t_ns,
        np.hstack([w_want.force_n, w_want.torque_nm]),
    )
    for name, series in result.session.markers.items():
        want = human_session.session.markers[name]
        assert_rows_from(series.t_ns, series.position_m, want.t_ns, want.position_m)
    for topic, rep in report.topics.items():
        assert rep.lost == rep.expected - rep.read, topic  # type: ignore[operator]
    with pytest.raises(BagCorruptError) as error:
        read_session(bag, strict=True)
    assert error.value.crc_errors == 1


def test_damage_without_metadata_yaml(human_session: SimulatedSession, write_bag: Callable[..., Path]) -> None:
    # A killed recorder leaves no metadata.yaml and no summary: the loss is unknown, and said so.
    bag = write_bag(human_session)
    (bag / "metadata.yaml").unlink()
    file = mcap_of(bag)
    pristine = file.read_bytes()
    file.write_bytes(pristine[: len(pristine) // 2])
    result = read_session(bag)
    assert result.report.truncated and result.report.lost_messages is None
    assert result.report.topics["/ft_sensor/wrench"].expected is None
    assert any("unknown" in w for w in result.report.warnings)
    # A CRC-failed chunk is counted from its message indexes even then.
    with file.open("wb") as stream:
        stream.write(pristine)
    with file.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    assert summary is not None
    chunk = summary.chunk_indexes[2]
    data = bytearray(pristine)
    data[chunk.chunk_start_offset + 9 + 40 + 100] ^= 0xFF
    file.write_bytes(bytes(data))
    damaged = read_session(bag).report
    assert damaged.crc_errors == 1
    lost = sum(t.lost or 0 for t in damaged.topics.values())
    total = sum(t.read for t in damaged.topics.values())
    assert lost > 0 and lost + total == sum(t.expected or 0 for t in damaged.topics.values())


def test_errors_are_distinct(tmp_path: Path) -> None:
    with pytest.raises(BagNotFoundError) as missing:
        read_session(tmp_path / "nowhere")
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "readme.txt").write_text("hello")
    with pytest.raises(NotABagError) as not_bag:
        read_session(tmp_path / "notes")
    fake = tmp_path / "fake.mcap"
    fake.write_bytes(b"not an mcap file at all")
    with pytest.raises(NotABagError):
        read_session(fake)
    (tmp_path / "badmeta").mkdir()
    (tmp_path / "badmeta" / "metadata.yaml").write_text("just: [a, list")
    with pytest.raises(NotABagError):
        read_session(tmp_path / "badmeta")
    codes = {missing.value.code, not_bag.value.code}
    assert codes == {"not-found", "not-a-bag"}
    assert all(isinstance(e.value, BagError) for e in (missing, not_bag))


def _empty_session(frame: str = "world") -> Session:
    empty_t = np.zeros(0, dtype=np.int64)
    empty_v = np.zeros((0, 3))
    return Session(
        WrenchSeries(empty_t, empty_v, empty_v, frame),
        {name: MarkerSeries(empty_t, empty_v) for name in ("shoulder", "elbow", "hand")},
    )


def test_empty_bag(tmp_path: Path) -> None:
    bag = write_session_bag(tmp_path / "empty", _empty_session())
    with pytest.raises(EmptyBagError) as error:
        read_session(bag)
    assert error.value.code == "empty"
    bare = tmp_path / "bare.mcap"
    with bare.open("wb") as stream:
        writer = Writer(stream)
        writer.start(profile="ros2")
        writer.finish()
    with pytest.raises(EmptyBagError):
        read_session(bare)


def test_missing_topic_names_it_and_lists_the_present(human_session: SimulatedSession, tmp_path: Path) -> None:
    markers = {k: v for k, v in human_session.session.markers.items() if k != "hand"}
    session = Session(human_session.session.wrench, markers, human_session.session.rotation_world_from_sensor)
    bag = write_session_bag(tmp_path / "nohand", session)
    with pytest.raises(MissingTopicError) as error:
        read_session(bag)
    message = str(error.value)
    assert error.value.topic == "/mocap/hand" and "/mocap/elbow" in message and "/ft_sensor/wrench" in message
    # The same bag read under another topic map finds its hand marker elsewhere.
    remapped = TopicMap(markers={**MARKER_TOPICS, "hand": "/mocap/wrist", "wrist": "/absent"})
    assert read_session(bag, topics=remapped).report.n_segments == 2


def _rosbags_bag(path: Path, wrench_type: str, extra_raw: bytes | None = None) -> Path:
    """A bag written by rosbags' own Writer (1 MiB chunks, no CRCs), optionally with a bad wrench type."""

    def types(name: str) -> type:
        return TYPESTORE.types[name]  # type: ignore[no-any-return]

    with RosbagsWriter(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        wrench = writer.add_connection("/ft_sensor/wrench", wrench_type, typestore=TYPESTORE)
        markers = {
            name: writer.add_connection(f"/mocap/{name}", "geometry_msgs/msg/PoseStamped", typestore=TYPESTORE)
            for name in ("shoulder", "elbow", "hand")
        }
        for i in range(1, 21):
            t = i * 10_000_000
            if wrench_type == "geometry_msgs/msg/WrenchStamped":
                msg = build_wrench_stamped(types, WrenchSample(t, "world", np.full(3, i * 1.0), np.zeros(3)))
            else:
                msg = types(wrench_type)(
                    force=types("geometry_msgs/msg/Vector3")(x=1.0, y=2.0, z=3.0),
                    torque=types("geometry_msgs/msg/Vector3")(x=0.0, y=0.0, z=0.0),
                )
            writer.write(wrench, t, TYPESTORE.serialize_cdr(msg, wrench_type))
            for connection in markers.values():
                pose = build_pose_stamped(types, PoseSample(t, "world", np.array([0.0, 0.1 * i, 1.0])))
                writer.write(connection, t, TYPESTORE.serialize_cdr(pose, "geometry_msgs/msg/PoseStamped"))
        if extra_raw is not None:
            writer.write(wrench, 10**9, extra_raw)
    return path


def test_wrong_message_type_names_both(tmp_path: Path) -> None:
    bag = _rosbags_bag(tmp_path / "wrongtype", "geometry_msgs/msg/Wrench")
    with pytest.raises(MessageTypeError) as error:
        read_session(bag)
    assert error.value.code == "wrong-type"
    assert "geometry_msgs/msg/Wrench," in str(error.value) + "," and "geometry_msgs/msg/WrenchStamped" in str(
        error.value
    )
    # Without metadata.yaml the MCAP schema names the type.
    (bag / "metadata.yaml").unlink()
    with pytest.raises(MessageTypeError):
        read_session(bag)


def test_rosbags_written_bag_without_crcs_and_an_undecodable_message(tmp_path: Path) -> None:
    bag = _rosbags_bag(tmp_path / "plain", "geometry_msgs/msg/WrenchStamped", extra_raw=b"\x00\x01\x00\x00\x01\x02")
    result = read_session(bag)
    report = result.report
    assert report.chunks_without_crc >= 1 and any("no CRC" in w for w in report.warnings)
    rep = report.topics["/ft_sensor/wrench"]
    assert (rep.read, rep.undecodable, rep.expected, rep.lost) == (20, 1, 21, 0)
    np.testing.assert_array_equal(result.session.wrench.force_n[:, 0], np.arange(1, 21))
    assert result.report.n_segments == 2


def test_missing_mcap_file_listed_in_metadata(human_session: SimulatedSession, write_bag: Callable[..., Path]) -> None:
    bag = write_bag(human_session)
    mcap_of(bag).unlink()
    with pytest.raises(BagCorruptError):
        read_session(bag)
    shutil.rmtree(bag)


def test_random_bit_flips_are_reported_never_returned_as_data(
    paper_session: SimulatedSession, write_bag: Callable[..., Path]
) -> None:
    bag = write_bag(paper_session)
    file = mcap_of(bag)
    pristine = file.read_bytes()
    want = paper_session.session
    rng = np.random.default_rng(11)
    for position in rng.integers(len(b"\x89MCAP0\r\n"), len(pristine), size=60).tolist():
        data = bytearray(pristine)
        data[position] ^= 1 << int(rng.integers(0, 8))
        file.write_bytes(bytes(data))
        try:
            result = read_session(bag)
        except BagError:
            continue  # refused outright: fine
        assert result.report.damaged, f"flip at byte {position} went unnoticed"
        got = result.session
        assert_rows_from(
            got.wrench.t_ns,
            np.hstack([got.wrench.force_n, got.wrench.torque_nm]),
            want.wrench.t_ns,
            np.hstack([want.wrench.force_n, want.wrench.torque_nm]),
        )
        for name, series in got.markers.items():
            assert_rows_from(series.t_ns, series.position_m, want.markers[name].t_ns, want.markers[name].position_m)


def test_tf_chain_is_composed_and_a_turning_link_gives_one_rotation_per_sample(tmp_path: Path) -> None:
    from msg_adapters import TransformSample, build_tf_message, matrix_from_quaternion

    def types(name: str) -> type:
        return TYPESTORE.types[name]  # type: ignore[no-any-return]

    bag = _rosbags_bag(tmp_path / "tfbag", "geometry_msgs/msg/WrenchStamped")
    # Re-home the wrench in a frame two TF hops from world: rewrite the bag with /tf_static + /tf.
    shutil.rmtree(bag)
    half = np.sqrt(0.5)
    with RosbagsWriter(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        wrench = writer.add_connection("/ft_sensor/wrench", "geometry_msgs/msg/WrenchStamped", typestore=TYPESTORE)
        markers = [
            writer.add_connection(f"/mocap/{n}", "geometry_msgs/msg/PoseStamped", typestore=TYPESTORE)
            for n in ("shoulder", "elbow", "hand")
        ]
        static = writer.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=TYPESTORE)
        dynamic = writer.add_connection("/tf", "tf2_msgs/msg/TFMessage", typestore=TYPESTORE)
        q_static = np.array([0.0, 0.0, half, half])  # 90 deg about z
        tf_static = build_tf_message(types, [TransformSample(1, "world", "robot", np.zeros(3), q_static)])
        writer.write(static, 1, TYPESTORE.serialize_cdr(tf_static, "tf2_msgs/msg/TFMessage"))
        for t, q in ((2, [1.0, 0.0, 0.0, 0.0]), (3, [np.nan, 0.0, 0.0, 1.0]), (4, [half, 0.0, 0.0, half])):
            msg = build_tf_message(types, [TransformSample(t, "robot", "ft", np.zeros(3), np.array(q))])
            writer.write(dynamic, t, TYPESTORE.serialize_cdr(msg, "tf2_msgs/msg/TFMessage"))
        for i in range(1, 6):
            sample = WrenchSample(10 + i, "ft", np.ones(3), np.zeros(3))
            writer.write(wrench, 10 + i, TYPESTORE.serialize_cdr(build_wrench_stamped(types, sample), wrench.msgtype))
            for connection in markers:
                pose = build_pose_stamped(types, PoseSample(10 + i, "world", np.zeros(3)))
                writer.write(connection, 10 + i, TYPESTORE.serialize_cdr(pose, connection.msgtype))
    result = read_session(bag)
    expected = matrix_from_quaternion(q_static) @ matrix_from_quaternion([half, 0.0, 0.0, half])
    # The /tf link turns (t = 2 and 4 ns): one rotation per wrench sample, the last one held after t = 4 ns
    # (within the quiet hold of a recording's edges: no warning).
    rotation = result.session.rotation_world_from_sensor
    assert rotation.shape == (5, 3, 3)
    np.testing.assert_allclose(rotation, np.broadcast_to(expected, (5, 3, 3)), atol=1e-12)
    assert result.report.rotation_source == "tf"
    assert result.report.topics["/tf"].non_finite == 1
    assert not any("outside its /tf samples" in w for w in result.report.warnings)
