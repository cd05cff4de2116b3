"""A session recorded message by message into its bag is stored as `bsp sessions add BAG` stores the same messages,
with the subject record's body data; a session that cannot be identified keeps its bag and says where."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from cli_run import bsp
from mcap.reader import make_reader

from bsp_ros.bag import TopicMap
from bsp_ros.bag.writer import write_session_bag
from bsp_ros.clinic.store import SessionRecord, SubjectRecord, open_store
from bsp_ros.core.simulation import SimulatedSession, human_arm_cell, simulate_cell
from bsp_ros.live.session.control import EndCause, SessionControl
from bsp_ros.live.session.recording import SessionRecording
from bsp_ros.live.session.storing import IdentifySettings, OutcomeKind, SessionJob, SessionOutcome, store_session

SUBJECT = "P007"
BODY: dict[str, Any] = {"body_mass_kg": 58.0, "height_m": 1.62, "sex": "female"}
DURATION_S = 50.0


@pytest.fixture(scope="module")
def simulated() -> SimulatedSession:
    """A female arm of the record's body data: the truth the stored session must hold."""
    return simulate_cell(human_arm_cell(sex="female", body_mass_kg=58.0, height_m=1.62, seed=11, duration_s=DURATION_S))


@pytest.fixture(scope="module")
def bag(simulated: SimulatedSession, tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_session_bag(tmp_path_factory.mktemp("bags") / "session", simulated.session)


def _messages(bag: Path) -> Iterator[tuple[str, int, bytes]]:
    """(topic, receive time ns, CDR) of every message of ``bag`` as a recorder received them: in log time order."""
    (mcap,) = bag.glob("*.mcap")
    with mcap.open("rb") as stream:
        for _, channel, message in make_reader(stream).iter_messages(log_time_order=True):
            yield channel.topic, message.log_time, message.data


def _store(path: Path) -> Path:
    with open_store(path) as store:
        store.set_subject(SubjectRecord(SUBJECT, arm="left", **BODY))
    return path


def _record_session(bag: Path, out: Path, topics: set[str] | None = None) -> tuple[SessionJob, int]:
    """Feed ``bag``'s messages (those of ``topics``) to a recording that starts with the wrench stream and ends with
    its silence; returns the finished session's job and the messages fed."""
    control = SessionControl(node_name="session_recorder", end_timeout_s=2.0, max_session_s=1800.0, auto_start=True)
    control.name_subject(SUBJECT)
    recording = SessionRecording(control, out, TopicMap(), with_tf=True)
    fed, last_ns = 0, 0
    for topic, t_ns, data in _messages(bag):
        if topics is None or topic in topics:
            recording.on_message(topic, t_ns, data)
            fed, last_ns = fed + 1, t_ns
    assert recording.tick(last_ns + 1_000_000_000).finished is None  # 1 s of silence: the session goes on
    change = recording.tick(last_ns + 2_500_000_000)
    assert change.finished is not None
    ended, spool = change.finished
    assert ended.cause is EndCause.SILENCE and ended.session.subject == SUBJECT
    job = SessionJob(ended=ended, spool=spool, store_location=None, settings=IdentifySettings())
    return job, fed


def _values(record: SessionRecord) -> dict[tuple[str, str, str], float | None]:
    return {key: q.value for key, q in record.parameters.items()}


@pytest.mark.slow
def test_a_recorded_session_is_stored_whole_with_the_subject_records_body_data(
    bag: Path, simulated: SimulatedSession, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    job, fed = _record_session(bag, tmp_path / "live_recordings")
    assert sum(job.spool.counts.values()) == fed
    store = _store(tmp_path / "live.sqlite")
    job = SessionJob(ended=job.ended, spool=job.spool, store_location=str(store), settings=job.settings)
    outcome = store_session(job, str(store))
    assert outcome.kind is OutcomeKind.STORED, outcome.log_line()
    assert outcome.valid, outcome.log_line()
    assert not job.spool.path.exists()  # stored valid: its bag is removed
    with open_store(store) as opened:
        (live,) = opened.sessions(SUBJECT)
    assert live.subject_info == BODY  # the prior is the record's, not the male population's
    assert live.arm == "left" and not live.retest
    # The whole session, not a 30 s window: the estimate spans the simulated session (less the filters' edges).
    assert outcome.estimate_s is not None and DURATION_S - 2.0 < outcome.estimate_s <= DURATION_S
    assert outcome.log_line().startswith(f"stored session 1 of {SUBJECT} (left arm, ")
    assert str(store) in outcome.log_line()

    # `bsp sessions add` on the bag the same messages came from stores the same numbers.
    other = _store(tmp_path / "offline.sqlite")
    code, _, err = bsp(capsys, "sessions", "add", str(bag), "--subject", SUBJECT, "--store", str(other))
    assert code == 0, err
    with open_store(other) as opened:
        (offline,) = opened.sessions(SUBJECT)
    assert offline.subject_info == BODY
    assert live.session_time_ns == offline.session_time_ns
    assert _values(live).keys() == _values(offline).keys()
    for key, value in _values(offline).items():
        assert _values(live)[key] == pytest.approx(value, rel=1e-9, abs=1e-12), key

    # And the truth of the simulated arm lies within the stored stds.
    truth = simulated.truth.static_moments_kgm
    for k, segment in enumerate(("upper_arm", "forearm", "hand")):
        q = live.parameters[("segments", segment, "static_moment_kgm")]
        assert q.value is not None and q.std is not None
        assert abs(q.value - truth[k]) < 3 * q.std, (segment, q.value, truth[k], q.std)


@pytest.mark.slow
def test_a_session_that_cannot_be_identified_keeps_its_bag_and_says_how_to_add_it(bag: Path, tmp_path: Path) -> None:
    job, _ = _record_session(bag, tmp_path / "live_recordings", topics={"/ft_sensor/wrench"})  # no marker
    store = _store(tmp_path / "live.sqlite")
    job = SessionJob(ended=job.ended, spool=job.spool, store_location=str(store), settings=job.settings)
    outcome: SessionOutcome = store_session(job, str(store))
    assert outcome.kind is OutcomeKind.FAILED
    assert outcome.kept == job.spool.path and (job.spool.path / "metadata.yaml").is_file()
    line = outcome.log_line()
    assert "NOT stored" in line and "/mocap/" in line  # the missing topic is named
    assert f"bsp sessions add {job.spool.path} --subject {SUBJECT}" in line
    with open_store(store) as opened:
        assert opened.sessions() == []


def test_a_session_without_a_wrench_leaves_nothing(bag: Path, tmp_path: Path) -> None:
    control = SessionControl(node_name="session_recorder", end_timeout_s=2.0, max_session_s=1800.0)
    control.name_subject(SUBJECT)
    recording = SessionRecording(control, tmp_path, TopicMap(), with_tf=True)
    reply, change = recording.start(1_700_000_000_000_000_000)
    assert reply.success and change.path is not None and change.path.is_dir()
    assert SUBJECT not in change.path.name  # a bag's name never carries the subject
    _, change = recording.stop(1_700_000_010_000_000_000)
    assert change.finished is not None
    _, spool = change.finished
    job = SessionJob(ended=change.finished[0], spool=spool, store_location=None, settings=IdentifySettings())
    outcome = store_session(job, "nowhere")
    assert outcome.kind is OutcomeKind.EMPTY and not spool.path.exists()
    assert "without a wrench message" in outcome.log_line()
