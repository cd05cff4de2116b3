"""`bsp watch`: the live table of any running cell. Its view against a real estimate of a simulated session (values,
stds, budgets, verdict and cause), counters at known rates, the precision block; the counters it reads against those
bsp_identifier counts; then `bsp watch` itself in tmux against a cell that publishes those messages over DDS and
against the real node suite on the simulated cell, and its exit codes."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from bsp_ros.cli.watch_view import ANGLES_LOST, IDENTIFIER_LOST, CounterRate, WatchView
from bsp_ros.core import simulation as sim
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import FindingCode, plain_cause
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.live.online.precision import PrecisionTarget, PrecisionTracker

ROOT = Path(__file__).resolve().parents[3]
#: The live tests' helpers (LiveCell: the node suite on a private domain).
LIVE_NODES = ROOT / "test" / "bsp_ros" / "live" / "nodes"
SEGMENTS = ("upper_arm", "forearm", "hand")


@pytest.fixture(scope="module")
def session() -> tuple[dict[str, Any], dict[str, Any]]:
    """A valid estimate of a 40 s simulated session (seeded) and the session's truth."""
    simulated = sim.simulate_cell(sim.human_arm_cell(seed=21, duration_s=40.0))
    return identify_session(simulated.session, IdentifyOptions()), simulated.truth.to_dict()


@pytest.fixture(scope="module")
def short_session() -> dict[str, Any]:
    """The estimate of the first 6 s of a session: too little motion, invalid."""
    simulated = sim.simulate_cell(sim.human_arm_cell(seed=22, duration_s=6.0))
    return identify_session(simulated.session, IdentifyOptions())


def _with_precision(document: dict[str, Any], percent: float, hold_s: float, times_s: list[float]) -> dict[str, Any]:
    """The document with the precision block a tracker gives after it came at each of ``times_s``."""
    tracker = PrecisionTracker(PrecisionTarget.static_moments(percent, SEGMENTS[:2], hold_s=hold_s))
    estimate = Estimate.from_json(document)
    state = None
    for t_s in times_s:
        state = tracker.update(estimate, int(t_s * 1e9))
    assert state is not None
    return {**document, "precision": state.to_json()}


def _line(table: str, start: str) -> str:
    return next(line for line in table.splitlines() if line.startswith(start))


def test_the_table_shows_each_parameter_with_its_std_its_largest_uncertainty_and_the_verdict(session: Any) -> None:
    document, truth = session
    assert document["quality"]["valid"]
    view = WatchView()
    view.on_estimate(json.dumps(document), 10.0)
    table = view.render(10.5, "header")
    assert table.splitlines()[0] == "header" and "VALID: " in table.splitlines()[1]
    assert "no estimate for" not in table and "cause:" not in table
    for segment in SEGMENTS:
        q = document["segments"][segment]["static_moment_kgm"]
        assert abs(q["value"] - truth["segments"][segment]["static_moment_kgm"]) < 3 * q["std"]  # a real estimate
        row = _line(table, f"{segment} static_moment_kgm")
        term = max(q["budget"], key=lambda k: q["budget"][k] or 0.0)
        share = 100 * q["budget"][term] ** 2 / q["std"] ** 2
        assert f"{q['value']:10.4f}" in row and f"{q['std']:9.2g}" in row
        assert f"{100 * q['std'] / abs(q['value']):7.2f}" in row and row.endswith(f"{term} {share:.0f} %")
    for joint in document["joints"]:
        assert f"{document['joints'][joint]['coulomb_nm']['value']:10.4f}" in _line(table, f"{joint} coulomb_nm")
    assert "weight support: none received (bsp_identifier's support_fraction is 0" in table
    view.on_support((1.5, -20.25, 0.125))
    assert "F_y +1.50 N, F_z -20.25 N, M_x +0.125 Nm" in view.render(10.5, "")
    assert "no estimate for 3.5 s" in view.render(13.5, "")  # the identifier went quiet
    assert view.exit_code() == 0


def test_an_invalid_estimate_says_its_cause_and_what_to_do(short_session: Any) -> None:
    document = short_session
    estimate = Estimate.from_json(document)
    assert not estimate.valid
    cause = plain_cause(estimate.quality.findings)
    assert cause is not None
    view = WatchView()
    assert view.exit_code() == 3  # nothing arrived
    view.on_estimate(json.dumps(document), 0.0)
    table = view.render(0.1, "")
    assert f"INVALID: {document['quality']['message']}" in table
    verdict = estimate.quality.verdict
    assert verdict is not None and verdict.code is FindingCode.ONE_DIRECTION  # 6 s: the shoulder has not turned
    assert f"  cause: {cause[0]}; what to do: {cause[1]}" in table.splitlines()
    assert view.exit_code() == 1
    view.on_estimate("not json", 0.2)
    view.on_estimate(json.dumps([1, 2]), 0.3)
    view.on_estimate(json.dumps({**document, "mode": "batch"}), 0.4)  # a mode this version does not know
    view.on_estimate(json.dumps({**document, "method": "stacked"}), 0.5)
    assert view.unreadable == 4 and view.estimates == 1
    view.on_estimate(json.dumps({**document, "mode": "recursive"}), 0.6)
    assert view.render(0.7, "").splitlines()[1].endswith(" (recursive)")  # the verdict line names the mode


def test_the_input_rates_and_losses_come_from_the_nodes_counters() -> None:
    view = WatchView()
    assert "wrench ? Hz" in view.render(0.0, "")
    for k in range(26):  # bsp_identifier at 5 Hz: 100 wrenches and 50 joint angles a second, 3 refused
        t_ns = 1_000_000_000 + k * 200_000_000
        values = {"wrench": str(20 * k), "joint_states": str(10 * k), "refused": "3", "waiting_for_tf": "0"}
        view.on_diagnostics("bsp_identifier", values, t_ns)
        if k % 5 == 0:  # joint_angle_estimator once a second: 49 frames a second, one incomplete
            estimator = {"frames": str(49 * k // 5), "incomplete_frames": str(k // 5), "rejected_frames": "0"}
            view.on_diagnostics("joint_angle_estimator", estimator, t_ns)
    rates = view.input_rates()
    assert rates.wrench_hz == pytest.approx(100.0) and rates.angles_hz == pytest.approx(50.0)
    assert rates.marker_frames_hz == pytest.approx(49.0)
    assert rates.lost["bsp_identifier.refused"] == 3 and rates.lost["joint_angle_estimator.incomplete_frames"] == 5
    lines = view.render(0.0, "").splitlines()
    assert lines[-2].startswith("inputs: wrench 100 Hz, joint angles 50 Hz") and "marker frames 49 Hz" in lines[-2]
    assert "bsp_identifier.refused 3" in lines[-1] and "joint_angle_estimator.incomplete_frames 5" in lines[-1]


def test_a_restarted_node_starts_its_rate_over_and_reordered_counters_are_skipped() -> None:
    rate = CounterRate(window_s=2.0)
    for k in range(30):
        rate.add(k * 0.2, 20 * k)
    assert rate.rate_hz == pytest.approx(100.0) and rate.samples[-1][0] - rate.samples[0][0] <= 2.0 + 1e-9
    rate.add(5.0, 100)  # stamped before the newest: skipped
    assert rate.samples[-1] == (pytest.approx(5.8), 580)
    rate.add(6.0, 10)  # the counter went back: the node restarted
    assert rate.rate_hz is None
    rate.add(6.5, 35)
    assert rate.rate_hz == pytest.approx(50.0)


def test_the_precision_line_follows_the_estimates_block_and_the_signal(session: Any) -> None:
    document, _ = session
    view = WatchView()
    view.on_estimate(json.dumps(document), 0.0)
    assert "precision: no target" in view.render(0.0, "")
    reached = _with_precision(document, 50.0, 1.0, [0.0, 0.5, 1.5])
    view.on_estimate(json.dumps(reached), 0.0)
    assert _line(view.render(0.0, ""), "precision:") == (
        "precision: REACHED 1.5 s into the session: the static moments of upper_arm, forearm within 50 % std"
    )
    holding = _with_precision(document, 50.0, 5.0, [0.0, 1.25])
    view.on_estimate(json.dumps(holding), 0.0)
    assert _line(view.render(0.0, ""), "precision:") == "precision: not yet: every target met for 1.2 of 5 s"
    tight = _with_precision(document, 0.01, 1.0, [0.0])
    worst = max(
        SEGMENTS[:2],
        key=lambda s: (
            document["segments"][s]["static_moment_kgm"]["std"]
            / abs(document["segments"][s]["static_moment_kgm"]["value"])
        ),
    )
    view.on_estimate(json.dumps(tight), 0.0)
    assert _line(view.render(0.0, ""), "precision:").startswith(f"precision: not yet: {worst} static_moment_kgm std ")
    view.on_precision(True)  # the latched topic says it came (an estimate's block may lag by one update)
    assert _line(view.render(0.0, ""), "precision:").startswith("precision: REACHED")


def test_the_precision_line_names_passive_targets_and_each_target_of_a_plan(session: Any) -> None:
    # A plan gives each static moment its own target; target_parameters may name a joint's passive term.
    document, _ = session
    limits = {("forearm", "static_moment_kgm"): 0.5, ("elbow", "coulomb_nm"): 0.9}
    state = PrecisionTracker(PrecisionTarget(relative_std=limits, hold_s=0.0)).update(Estimate.from_json(document), 0)
    for (owner, key), limit in limits.items():  # the simulated session's estimate is within both
        group = "segments" if owner == "forearm" else "joints"
        assert document[group][owner][key]["std"] <= limit * abs(document[group][owner][key]["value"])
    view = WatchView()
    view.on_estimate(json.dumps({**document, "precision": state.to_json()}), 0.0)
    assert _line(view.render(0.0, ""), "precision:") == (
        "precision: REACHED 0.0 s into the session: forearm static_moment_kgm within 50 %, elbow coulomb_nm within "
        "90 % std"
    )
    same = PrecisionTarget(relative_std=dict.fromkeys(limits, 0.9), hold_s=0.0)
    view.on_estimate(
        json.dumps({**document, "precision": PrecisionTracker(same).update(Estimate.from_json(document), 0).to_json()}),
        0.0,
    )
    assert _line(view.render(0.0, ""), "precision:").endswith(
        ": forearm static_moment_kgm, elbow coulomb_nm within 90 % std"
    )


def test_the_lost_counters_watch_reads_are_those_bsp_identifier_counts() -> None:
    # The identifier's counters come from LiveIdentifier (the node publishes them on /diagnostics as they are): a
    # wrench before its frame's first transform, a wrench of another frame than the tare's; refused from the start.
    import numpy as np

    from bsp_ros.core.tare import Tare
    from bsp_ros.live.online.identifier_settings import IdentifierSettings
    from bsp_ros.live.online.live_identifier import LiveIdentifier
    from bsp_ros.live.online.wrench_input import WrenchInput
    from msg_adapters.wrench import WrenchSample

    identifier = LiveIdentifier(IdentifierSettings.from_parameters({}), lambda estimate: estimate, pytest.fail)
    assert {"wrench", "joint_states", "refused"} <= set(identifier.counters())  # counted from the start
    sample = WrenchSample(1_000_000_000, "ft_sensor", np.array([0.0, 1.0, -20.0]), np.zeros(3))
    identifier.add_wrench(sample, None)  # no transform yet
    tare = Tare(
        frame_id="another_sensor",
        load="constant",
        values=np.zeros(6),
        covariance=np.zeros((6, 6)),
        n_samples=100,
        start_time_ns=0,
        duration_s=10.0,
    )
    identifier.wrench_input = WrenchInput(tare, 0.0)
    identifier.add_wrench(sample, np.eye(3))
    counters = identifier.counters()
    assert counters["waiting_for_tf"] == 1 and counters["tare_frame_mismatch"] == 1
    assert set(IDENTIFIER_LOST) <= set(counters)
    view = WatchView()
    view.on_diagnostics("bsp_identifier", {k: str(v) for k, v in counters.items()}, 1)
    assert {f"bsp_identifier.{key}" for key in IDENTIFIER_LOST} <= set(view.input_rates().lost)


# -- bsp watch itself, over DDS ---------------------------------------------------------------------------------


class RecordedCell:
    """Publishes what a cell's nodes publish, from recorded messages: the estimate JSON, bsp_identifier's and
    joint_angle_estimator's /diagnostics counters at known rates, the weight support and the precision signal."""

    WRENCH_HZ, ANGLES_HZ, FRAMES_HZ = 100, 50, 49

    def __init__(self, domain: int, document: dict[str, Any]) -> None:
        from bsp_ros.live.runtime.qos import QosSpec
        from bsp_ros.live.runtime.ros import Client

        self.client = Client("recorded_cell", domain)
        self.document = json.dumps(document)
        self.estimate = self.client.publisher("std_msgs/msg/String", "bsp/estimate_json", "estimates")
        self.diagnostics = self.client.publisher("diagnostic_msgs/msg/DiagnosticArray", "/diagnostics", "default")
        self.support = self.client.publisher("geometry_msgs/msg/WrenchStamped", "bsp/weight_support", "default")
        latched = QosSpec(reliable=True, depth=1, transient_local=True)
        self.precision = self.client.publisher("std_msgs/msg/Bool", "bsp/precision_reached", latched)
        self.start = time.monotonic()
        self.ticks = 0

    def tick(self) -> None:
        """One 5 Hz update: the estimate, bsp_identifier's counters; once a second the angle estimator's."""
        from bsp_ros.live.runtime.ros import message_class
        from msg_adapters.diagnostics import DiagnosticArraySample, DiagnosticStatusData, build_diagnostic_array

        elapsed = time.monotonic() - self.start
        stamp = time.time_ns()
        self.estimate.publish(message_class("std_msgs/msg/String")(data=self.document))
        values = {"wrench": int(self.WRENCH_HZ * elapsed), "joint_states": int(self.ANGLES_HZ * elapsed), "refused": 2}
        statuses = [DiagnosticStatusData.with_values(0, "bsp_identifier", "ok", "", values)]
        if self.ticks % 5 == 0:
            frames = {"frames": int(self.FRAMES_HZ * elapsed), "incomplete_frames": 7, "rejected_frames": 0}
            statuses.append(DiagnosticStatusData.with_values(0, "joint_angle_estimator", "tracking", "", frames))
        for status in statuses:
            sample = DiagnosticArraySample(stamp, "", (status,))
            self.diagnostics.publish(build_diagnostic_array(message_class, sample))
        wrench = message_class("geometry_msgs/msg/WrenchStamped")()
        wrench.header.frame_id = "world"
        wrench.wrench.force.y, wrench.wrench.force.z, wrench.wrench.torque.x = 0.5, 12.25, 0.0
        self.support.publish(wrench)
        if self.ticks == 0:
            self.precision.publish(message_class("std_msgs/msg/Bool")(data=True))
        self.ticks += 1

    def run_until(self, done: Any, timeout_s: float) -> bool:
        """Tick at 5 Hz until ``done()`` or the timeout."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            self.tick()
            if done():
                return True
            self.client.spin(0.2)
        return False

    def close(self) -> None:
        self.client.close()


class Tmux:
    """A tmux server of its own (a private socket) running one command in a wide pane."""

    def __init__(self, command: list[str], env: dict[str, str], width: int = 150) -> None:
        self.socket = f"bsp_watch_test_{os.getpid()}"
        exports = " ".join(f"{k}={v}" for k, v in env.items())
        line = f"env {exports} " + " ".join(command)
        subprocess.run(
            ["tmux", "-L", self.socket, "new-session", "-d", "-s", "watch", "-x", str(width), "-y", "45", line],
            check=True,
        )

    def capture(self) -> str:
        done = subprocess.run(
            ["tmux", "-L", self.socket, "capture-pane", "-p", "-t", "watch"], capture_output=True, text=True
        )
        return done.stdout

    def close(self) -> None:
        subprocess.run(["tmux", "-L", self.socket, "kill-server"], capture_output=True)


@pytest.fixture
def recorded_cell(ros_domain: int, session: Any) -> Iterator[tuple[int, RecordedCell, dict[str, Any]]]:
    document = _with_precision(session[0], 50.0, 1.0, [0.0, 0.5, 2.0])
    cell = RecordedCell(ros_domain, document)
    yield ros_domain, cell, document
    cell.close()


def _env() -> dict[str, str]:
    return {"PYTHONPATH": str(ROOT), "HOME": os.environ.get("HOME", "/tmp"), "TERM": "xterm"}


@pytest.mark.dds
@pytest.mark.skipif(shutil.which("tmux") is None, reason="needs tmux")
def test_bsp_watch_in_a_terminal_shows_the_estimate_its_verdict_precision_and_the_rates(recorded_cell: Any) -> None:
    domain, cell, document = recorded_cell
    tmux = Tmux([sys.executable, "-m", "bsp_ros.cli", "watch", "--domain", str(domain), "--interval", "0.5"], _env())
    try:

        def shown() -> bool:
            screen = tmux.capture()
            return "wrench 100 Hz" in screen and "marker frames 49 Hz" in screen and "REACHED" in screen

        assert cell.run_until(shown, 30), tmux.capture()
        screen = tmux.capture()
    finally:
        tmux.close()
    lines = screen.splitlines()
    assert lines[0].startswith(f"bsp watch: ROS domain {domain}")
    assert lines[1].startswith("VALID: ") and "cause:" not in screen
    assert (
        "precision: REACHED 2.0 s into the session: the static moments of upper_arm, forearm within 50 % std" in lines
    )
    for segment in SEGMENTS:
        q = document["segments"][segment]["static_moment_kgm"]
        assert f"{q['value']:10.4f} {q['std']:9.2g}" in _line(screen, f"{segment} static_moment_kgm")
    assert "F_y +0.50 N, F_z +12.25 N, M_x +0.000 Nm" in screen
    assert "joint angles 50 Hz" in screen
    assert "bsp_identifier.refused 2" in screen and "joint_angle_estimator.incomplete_frames 7" in screen


@pytest.mark.dds
def test_bsp_watch_once_prints_one_table_and_exits_by_the_last_estimate(recorded_cell: Any, ros_domains: Any) -> None:
    domain, cell, _ = recorded_cell
    command = [sys.executable, "-m", "bsp_ros.cli", "watch", "--domain", str(domain), "--once"]
    watch = subprocess.Popen(command, env={**os.environ, **_env()}, stdout=subprocess.PIPE, text=True)
    cell.run_until(lambda: watch.poll() is not None, 30)
    out, _ = watch.communicate(timeout=10)
    assert watch.returncode == 0, out
    assert out.count("bsp watch: ROS domain") == 1 and "VALID: " in out and "wrench 100 Hz" in out
    empty = subprocess.run(
        [*command[:-2], str(ros_domains()), "--once", "--timeout", "1"],
        env={**os.environ, **_env()},
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert empty.returncode == 3 and "waiting for the first estimate" in empty.stdout


def test_bad_options_exit_2_with_one_line() -> None:
    for argv in (["--duration", "0"], ["--domain", "300", "--once"], ["--interval", "-1"]):
        done = subprocess.run(
            [sys.executable, "-m", "bsp_ros.cli", "watch", *argv],
            env={**os.environ, **_env()},
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert done.returncode == 2, (argv, done.stderr)
        assert "Traceback" not in done.stderr and done.stderr.strip().splitlines()[-1].startswith("bsp watch: error")


#: The simulated cell's rates (wrench, marker frames) at 1x, and the speed the real suite runs at.
SIM_WRENCH_HZ, SIM_FRAMES_HZ, SIM_SPEED = 100.0, 50.0, 3.0


def _rate_on(screen: str, label: str) -> float | None:
    """The rate `bsp watch` shows after ``label`` (``wrench``, ``joint angles``, ``marker frames``), Hz."""
    line = next((x for x in screen.splitlines() if x.startswith("inputs: ")), "")
    words = line.split(f"{label} ", 1)
    if len(words) < 2 or not words[1].split(" ", 1)[0].isdigit():
        return None
    return float(words[1].split(" ", 1)[0])


@pytest.mark.dds
@pytest.mark.slow
@pytest.mark.skipif(shutil.which("tmux") is None, reason="needs tmux")
def test_bsp_watch_in_a_terminal_shows_the_real_node_suite(ros_domain: int) -> None:
    # The simulator, joint angle estimator and identifier as processes. The identifier waits for a transform on a
    # topic nobody publishes, so it counts the wrenches of its first 2 s as waiting_for_tf (then takes the stated
    # rotation, the simulated sensor's): a lost counter that is not 0.
    sys.path.insert(0, str(LIVE_NODES))
    from live_cell import LiveCell

    from msg_adapters.diagnostics import read_diagnostic_array

    published: dict[str, set[str]] = {}

    def hear(c: Any) -> None:
        def on_diagnostics(msg: Any) -> None:
            for status in read_diagnostic_array(msg).status:
                published.setdefault(status.name, set()).update(dict(status.values))

        c.client.subscribe("diagnostic_msgs/msg/DiagnosticArray", "/diagnostics", on_diagnostics, "default")

    identifier = ["wrench_frame_source:=topic", "wrench_frame_topic:=ft_sensor/not_published"]
    cell = LiveCell(ros_domain, [f"speed:={SIM_SPEED}", "seed:=4"], identifier, before_start=hear)
    command = [sys.executable, "-m", "bsp_ros.cli", "watch", "--domain", str(ros_domain), "--interval", "0.5"]
    tmux = Tmux(command, _env(), width=300)  # the lost counters of both nodes on one line
    try:

        def shown() -> bool:
            screen = tmux.capture()
            rates = [_rate_on(screen, label) for label in ("wrench", "joint angles", "marker frames")]
            return "VALID: " in screen and "INVALID" not in screen and None not in rates

        assert cell.spin_until(shown, 60), tmux.capture()
        cell.spin_until(lambda: False, 6.0)  # the rates over their full 5 s span
        screen = tmux.capture()
        valid = [d for _, d in cell.estimates if d["quality"]["valid"]]
    finally:
        tmux.close()
        cell.close()
    lines = screen.splitlines()
    assert lines[0].startswith(f"bsp watch: ROS domain {ros_domain}") and lines[1].startswith("VALID: "), screen
    # Each static moment with its std as one of the estimates the identifier published.
    assert valid
    for segment in SEGMENTS:
        row = _line(screen, f"{segment} static_moment_kgm")
        cells = {
            f"{d['segments'][segment]['static_moment_kgm']['value']:10.4f} "
            f"{d['segments'][segment]['static_moment_kgm']['std']:9.2g}"
            for d in valid
        }
        assert any(c in row for c in cells), row
    # The rates the simulator streams at (3x its 100 Hz wrench and 50 Hz marker frames).
    for label, hz in (("wrench", SIM_WRENCH_HZ), ("joint angles", SIM_FRAMES_HZ), ("marker frames", SIM_FRAMES_HZ)):
        shown_hz = _rate_on(screen, label)
        assert shown_hz is not None and abs(shown_hz - SIM_SPEED * hz) < 0.15 * SIM_SPEED * hz, (label, screen)
    # The lost counters: named as the nodes publish them, the waiting wrenches counted.
    assert {"wrench", "joint_states", *IDENTIFIER_LOST[:2]} <= published["bsp_identifier"], published
    assert {"frames", *ANGLES_LOST} <= published["joint_angle_estimator"], published
    lost = _line(screen, "lost (received, not usable")
    for key in (*IDENTIFIER_LOST[:2], *ANGLES_LOST):
        node = "bsp_identifier" if key in IDENTIFIER_LOST[:2] else "joint_angle_estimator"
        assert f"{node}.{key} " in lost, (key, lost)
    waiting = int(lost.split("bsp_identifier.waiting_for_tf ", 1)[1].split(",", 1)[0])
    assert waiting > 0, lost
