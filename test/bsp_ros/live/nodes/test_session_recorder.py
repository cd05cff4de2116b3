"""session_recorder on real rclpy and DDS, with the simulated cell: a retest started by service for a named subject is
stored whole under that subject, as a retest, with its record's body data; without a subject nothing is recorded and
the log says how to name one; the stop and reset services end and discard sessions."""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from node_processes import NodeProcesses, Peer
from ros_domains import next_domain_id

from bsp_ros.bag.cell_metadata import CELL_KEYS, SHIPPED_NOTE
from bsp_ros.bag.metadata import read_metadata
from bsp_ros.bag.topics import TF_TYPE
from bsp_ros.cell import SHIPPED_CELL
from bsp_ros.clinic.store import SubjectRecord, open_store
from bsp_ros.live.runtime.ros import has_message

pytestmark = [pytest.mark.dds, pytest.mark.slow]

SUBJECT = "P007"
BODY: dict[str, Any] = {"body_mass_kg": 66.0, "height_m": 1.68, "sex": "female"}
# Simulated seconds per wall second: the 44 s session takes 15 s. What streams between the simulator's start and
# the session's (about 1.4 s of wall time) is not recorded: 4 s of the session at 3x, which leave it 40 s.
SIM_DURATION_S = 44.0
SPEED = 3.0


class InProcessRecorder:
    """A SessionRecorderNode in this process (rclpy's default context) on its own domain, spun by the production
    executor in a thread, as `ros2 run` spins it."""

    def __init__(self, domain: int, params: list[str]) -> None:
        import rclpy

        from bsp_ros.live.nodes.session_recorder import SessionRecorderNode
        from bsp_ros.live.runtime.ros import make_executor

        rclpy.init(args=["--ros-args", *[a for p in params for a in ("-p", p)]], domain_id=domain)
        self.node = SessionRecorderNode()
        self.executor, _ = make_executor()
        self.executor.add_node(self.node)
        self.running = True
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self) -> None:
        import rclpy

        while self.running and rclpy.ok():
            self.executor.spin_once(timeout_sec=0.05)

    def close(self) -> None:
        import rclpy

        self.running = False
        self.thread.join(5)
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown()


def _call(peer: Peer, service: str, timeout_s: float = 10.0) -> Any:
    """Call a std_srvs/Trigger service of the recorder from the peer; its response."""
    from std_srvs.srv import Trigger

    client = peer.client.node.create_client(Trigger, service)
    assert peer.spin_until(client.service_is_ready, timeout_s), f"{service} not offered"
    future = client.call_async(Trigger.Request())
    assert peer.spin_until(future.done, timeout_s), f"{service} did not answer"
    return future.result()


@pytest.fixture
def cell(tmp_path: Path) -> Iterator[tuple[Callable[[], InProcessRecorder], NodeProcesses, Peer, Path]]:
    """The recorder (its first lines are the test's: started in the test's call, not its setup), the simulated
    cell's process and a peer, on a domain of their own."""
    domain = next_domain_id()
    store = tmp_path / "clinic.sqlite"
    with open_store(store) as opened:
        opened.set_subject(SubjectRecord(SUBJECT, arm="right", **BODY))
    params = [
        f"store:={store}",
        f"recordings_dir:={tmp_path / 'recordings'}",
        "end_timeout_s:=1.0",
        "auto_start:=false",  # the sensor's mounting comes from the shipped cell description, the simulator's
    ]
    nodes = NodeProcesses(domain, tmp_path)
    peer = Peer(domain)
    made: list[InProcessRecorder] = []

    def start() -> InProcessRecorder:
        made.append(InProcessRecorder(domain, params))
        return made[0]

    yield start, nodes, peer, store
    nodes.close()
    peer.close()
    for recorder in made:
        recorder.close()


Cell = tuple[Callable[[], InProcessRecorder], NodeProcesses, Peer, Path]


def _store_first_session_of_today(store: Path) -> int | None:
    """Store a session of the subject's right arm at the start of today (UTC), as an earlier session of the day;
    its id."""
    import time

    from bsp_ros.clinic.store.samples import sample_estimate

    day_ns = 86_400 * 10**9
    with open_store(store) as opened:
        stored = opened.add_estimate(sample_estimate(1, start_time_ns=time.time_ns() // day_ns * day_ns), SUBJECT)
    return stored.id


def test_a_retest_started_for_a_named_subject_is_stored_whole_as_a_retest_with_its_body_data(
    cell: Cell, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    from rclpy.parameter import Parameter

    start, nodes, peer, store = cell
    node = start().node
    # No subject: the start is refused, saying how to name one, and the streaming cell records nothing.
    truth = peer.listen_json("sim/truth", "tf_static_listener")
    refused = _call(peer, "bsp/session/start")
    assert not refused.success and "ros2 param set /session_recorder subject" in refused.message
    nodes.start(
        "cell_simulator",
        ["wait_for_subscribers:=1", f"speed:={SPEED}", f"duration_s:={SIM_DURATION_S}", "seed:=3"],
    )
    assert peer.spin_until(lambda: node.recording.control.last_input_ns is not None, 30), nodes.log("cell_simulator")
    peer.spin_until(lambda: False, 1.0)
    assert not (tmp_path / "recordings").exists() or not any((tmp_path / "recordings").iterdir())

    # Name the subject (as `ros2 param set` does: the same callback); a name-like id is refused.
    first_of_day = _store_first_session_of_today(store)  # a retest pairs with it
    (named_badly,) = node.set_parameters([Parameter("subject", value="Maria_Garcia")])
    assert not named_badly.successful and "name" in named_badly.reason
    (named,) = node.set_parameters([Parameter("subject", value=SUBJECT)])
    assert named.successful, named.reason
    started = _call(peer, "bsp/session/start_retest")
    assert started.success, started.message
    assert not _call(peer, "bsp/session/start").success  # one session at a time
    # The simulated session ends; its silence ends the recording, which is identified off the executor thread.
    assert peer.spin_until(lambda: bool(node.outcomes), SIM_DURATION_S / SPEED + 30), nodes.log("cell_simulator")
    (outcome,) = node.outcomes
    assert outcome.kind == "stored", outcome.log_line()

    with open_store(store) as opened:
        first, record = opened.sessions()
    assert first.id == first_of_day and not first.retest
    assert record.subject == SUBJECT
    assert record.subject_info == BODY  # the prior from the subject's record, not the male population's
    assert record.arm == "right"
    assert record.retest  # started by bsp/session/start_retest: the same day's retest
    # The simulated arm's truth within 3 std (the sensor's mounting written into the bag from the cell description).
    assert outcome.valid, outcome.log_line()
    assert truth, "no sim/truth"
    for segment, true in truth[-1][1]["segments"].items():
        q = record.parameters[("segments", segment, "static_moment_kgm")]
        assert q.value is not None and q.std is not None
        assert abs(q.value - true["static_moment_kgm"]) < 3 * q.std, (segment, q.value, true, q.std)
    # The whole session (from the start call to the simulator's end), not the identifier's 30 s window.
    assert outcome.estimate_s is not None and 32.0 < outcome.estimate_s <= SIM_DURATION_S
    assert (record.quality.n_samples or 0) > 30 * 100  # the wrench at 100 Hz

    log = capfd.readouterr().err
    assert "no subject named: nothing is recorded" in log
    assert "the wrench streams in but no subject is named" in log
    assert f"recording sessions for {SUBJECT} into {store}" in log
    assert f"retest of {SUBJECT} started (service)" in log
    assert f"stored session 2 of {SUBJECT} (right arm, retest" in log
    # The cell file it used, named once, plainly the shipped simulated cell's.
    assert log.count(f"cell: cell file {SHIPPED_CELL}: {SHIPPED_NOTE}") == 1
    assert not any((tmp_path / "recordings").iterdir()) or not outcome.valid  # a valid session's bag is removed


def test_stop_reset_and_session_end_end_sessions_and_one_that_cannot_be_identified_keeps_its_bag(
    cell: Cell, capfd: pytest.CaptureFixture[str]
) -> None:
    import numpy as np
    from rclpy.parameter import Parameter

    from bsp_ros.live.runtime.ros import message_class
    from msg_adapters.wrench import WrenchSample, build_wrench_stamped

    start, _, peer, store = cell
    node = start().node
    (named,) = node.set_parameters([Parameter("subject", value=SUBJECT)])
    assert named.successful
    wrench = peer.client.publisher("geometry_msgs/msg/WrenchStamped", "/ft_sensor/wrench", "sensor_data")
    end = peer.string_publisher("bsp/session_end")

    def stream() -> Path:
        """50 wrenches and no marker (a session that cannot be identified) into the running session's bag."""
        t0_ns = node.now_ns()
        for k in range(50):
            sample = WrenchSample(t0_ns + k * 10_000_000, "ft_sensor", np.array([0.0, 1.0, -20.0]), np.zeros(3))
            wrench.publish(build_wrench_stamped(message_class, sample))
            peer.spin_until(lambda: False, 0.01)
        assert peer.spin_until(lambda: bool(node.recording.spool and node.recording.spool.counts), 5)
        assert node.recording.spool is not None
        return Path(node.recording.spool.path)

    for service in ("bsp/session/stop", "bsp/session/reset"):  # nothing records yet
        refused = _call(peer, service)
        assert not refused.success and "no session" in refused.message, (service, refused.message)
    # start, reset: the first session's bag is deleted, nothing stored, and a new session records for the subject.
    assert _call(peer, "bsp/session/start").success
    discarded = stream()
    reset = _call(peer, "bsp/session/reset")
    assert reset.success and f"session of {SUBJECT} discarded" in reset.message, reset.message
    assert not discarded.exists()
    # stop: the new session ends and is identified (it cannot be: its bag is kept).
    kept = stream()
    assert kept != discarded
    stopped = _call(peer, "bsp/session/stop")
    assert stopped.success, stopped.message
    assert peer.spin_until(lambda: bool(node.outcomes), 20)
    (by_stop,) = node.outcomes
    assert by_stop.kind == "failed" and not by_stop.retest and by_stop.kept == kept
    assert not _call(peer, "bsp/session/stop").success  # it ended
    # A retest ended by a message on bsp/session_end.
    assert _call(peer, "bsp/session/start_retest").success
    stream()
    assert peer.spin_until(lambda: end.publisher.get_subscription_count() > 0, 10)  # type: ignore[attr-defined]
    end("")
    assert peer.spin_until(lambda: len(node.outcomes) == 2, 20)
    outcome = node.outcomes[1]
    assert outcome.kind == "failed" and outcome.retest
    assert outcome.kept is not None and (outcome.kept / "metadata.yaml").is_file()
    assert (by_stop.kept / "metadata.yaml").is_file()
    # Without tf2_msgs each bag states the mounting, from the shipped simulated cell's file, and says so.
    custom = read_metadata(by_stop.kept / "metadata.yaml").custom
    if not has_message(TF_TYPE):
        assert custom[CELL_KEYS["file"]] == str(SHIPPED_CELL) and custom[CELL_KEYS["shipped"]] == "true", custom
    with open_store(store) as opened:
        assert opened.sessions() == []
    log = capfd.readouterr().err
    assert f"session of {SUBJECT} started (service)" in log and f"session of {SUBJECT} started (reset)" in log
    assert f"session of {SUBJECT} discarded (reset): {discarded} deleted" in log
    assert f"session of {SUBJECT} ended (stop" in log
    assert "retest of P007 started (service)" in log
    assert "session of P007 ended (session_end" in log
    # The command carries the recorder's own settings (topics, cell file), so it stores the bag as the node would.
    logged = log.split(f"kept at {outcome.kept}: add it with `")[1].split("`")[0]
    assert logged.startswith(f"bsp sessions add {outcome.kept} --subject P007 --retest --method joint")
    assert "--cell-file" in logged
