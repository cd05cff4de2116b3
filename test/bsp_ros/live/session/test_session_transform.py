"""A sensor that turns with the handle, on a machine without tf2_msgs: the recorder records the cell's TransformStamped
topic into the session's bag (and the cell's mounting into its metadata), so the stored session is identified with
the rotation at each wrench sample, as `bsp identify` identifies the cell's own recording."""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from bsp_ros.bag import TopicMap, write_session_bag
from bsp_ros.bag.metadata import read_metadata
from bsp_ros.bag.offline import identify_bag
from bsp_ros.cell import read_cell_file
from bsp_ros.clinic.store import SubjectRecord, open_store
from bsp_ros.core.simulation import SimulatedSession, human_arm_cell, simulate_cell
from bsp_ros.live.session.control import SessionControl
from bsp_ros.live.session.recording import SessionRecording, topic_types
from bsp_ros.live.session.storing import IdentifySettings, OutcomeKind, SessionJob, cell_file_for, store_session
from msg_adapters import TransformSample, quaternion_from_matrix

CELL = read_cell_file()  # the shipped cell: the simulator's mounting and transform topic
SUBJECT = "P011"
DURATION_S = 40.0

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def turning() -> SimulatedSession:
    spec = human_arm_cell(seed=21, duration_s=DURATION_S)
    return simulate_cell(replace(spec, sensor=replace(spec.sensor, turns_with_handle=True)))


@pytest.fixture(scope="module")
def cell_bag(turning: SimulatedSession, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """What the cell sends without tf2_msgs: the sensor's rotation on its TransformStamped topic, no /tf_static."""
    frame = turning.session.wrench.frame_id
    samples = [
        TransformSample(int(t), CELL.world_frame, frame, np.zeros(3), quaternion_from_matrix(r))
        for t, r in zip(turning.tf_t_ns.tolist(), turning.tf_rotations_world_from_sensor, strict=True)
    ]
    out = tmp_path_factory.mktemp("cell") / "turning"
    return write_session_bag(out, turning.session, tf_static=False, transform_samples=samples)


def _messages(bag: Path) -> Iterator[tuple[str, int, bytes]]:
    (mcap,) = bag.glob("*.mcap")
    with mcap.open("rb") as stream:
        for _, channel, message in make_reader(stream).iter_messages(log_time_order=True):
            yield channel.topic, message.log_time, message.data


def _record(bag: Path, out: Path, recorded: set[str]) -> SessionJob:
    """Feed ``bag``'s messages on the topics a recorder without tf2_msgs subscribes to (``recorded``) into a
    recording of the shipped cell; the session ends with the wrench's silence."""
    control = SessionControl(node_name="session_recorder", end_timeout_s=2.0, max_session_s=1800.0, auto_start=True)
    control.name_subject(SUBJECT)
    topics = replace(TopicMap(), transform=CELL.transform_topic)
    recording = SessionRecording(control, out, topics, with_tf=False, rotation_xyzw=CELL.rotation_xyzw, cell=CELL)
    last_ns = 0
    for topic, t_ns, data in _messages(bag):
        if topic in recorded:
            recording.on_message(topic, t_ns, data)
            last_ns = t_ns
    change = recording.tick(last_ns + 2_500_000_000)
    assert change.finished is not None
    ended, spool = change.finished
    settings = IdentifySettings(topics=topics, cell_file=cell_file_for(CELL, CELL.rotation_xyzw, ""))
    return SessionJob(ended=ended, spool=spool, store_location=None, settings=settings, keep_recording=True)


def _store(path: Path) -> Path:
    with open_store(path) as store:
        store.set_subject(SubjectRecord(SUBJECT, arm="right", body_mass_kg=75.0, height_m=1.78, sex="male"))
    return path


def test_without_tf2_msgs_the_recorder_records_the_transform_topic_and_the_session_identifies(
    turning: SimulatedSession, cell_bag: Path, tmp_path: Path
) -> None:
    types = topic_types(replace(TopicMap(), transform=CELL.transform_topic), with_tf=False)
    assert types[CELL.transform_topic] == "geometry_msgs/msg/TransformStamped" and "/tf_static" not in types
    job = _record(cell_bag, tmp_path / "live_recordings", set(types))
    assert job.spool.counts[CELL.transform_topic] >= turning.tf_t_ns.size
    custom = read_metadata(job.spool.path / "metadata.yaml").custom
    assert custom["bsp_ros.cell.file"] == CELL.source and custom["bsp_ros.cell.sensor_frame"] == "ft_sensor"
    np.testing.assert_allclose(json.loads(custom["bsp_ros.cell.rotation_xyzw"]), CELL.rotation_xyzw)

    store = _store(tmp_path / "clinic.sqlite")
    outcome = store_session(replace(job, store_location=str(store)), str(store))
    assert outcome.kind is OutcomeKind.STORED and outcome.valid, outcome.log_line()
    with open_store(store) as opened:
        (stored,) = opened.sessions(SUBJECT)
    for k, segment in enumerate(("upper_arm", "forearm", "hand")):
        q = stored.parameters[("segments", segment, "static_moment_kgm")]
        assert q.value is not None and q.std is not None
        assert abs(q.value - turning.truth.static_moments_kgm[k]) < 3 * q.std, (segment, q)

    # The kept bag reads as the cell's own recording: the rotation per wrench sample, from the transform topic.
    document, reference = identify_bag(job.spool.path), identify_bag(cell_bag)
    assert document["quality"]["rotation"]["source"] == "topic" and document["quality"]["rotation"]["per_sample"]
    for segment, q in reference["segments"].items():
        value = document["segments"][segment]["static_moment_kgm"]["value"]
        assert value == pytest.approx(q["static_moment_kgm"]["value"], rel=1e-6), segment


def test_without_the_transform_topic_the_mounting_alone_cannot_fit_a_turning_sensor(
    cell_bag: Path, tmp_path: Path
) -> None:
    """What the recorder kept before it recorded the transform topic: the cell's fixed mounting only."""
    job = _record(cell_bag, tmp_path / "live_recordings", {"/ft_sensor/wrench", *TopicMap().markers.values()})
    assert CELL.transform_topic not in job.spool.counts
    document = identify_bag(job.spool.path)
    assert document["bag"]["rotation_source"] == "metadata"  # the mounting the bag's metadata states
    assert not document["quality"]["valid"]
