"""The node suite on rclpy + Fast DDS, in separate processes, against the simulated truth."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pytest
from live_cell import Estimates, LiveCell, wrench_frame_parameter
from ros_domains import next_domain_id

from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.model import contact_jacobian, gravity_regressor
from bsp_ros.live.runtime.qos import QosSpec
from bsp_ros.live.runtime.ros import Client
from msg_adapters.diagnostics import read_diagnostic_array
from msg_adapters.joint_state import read_joint_state
from msg_adapters.wrench import read_wrench_stamped

pytestmark = [pytest.mark.dds, pytest.mark.slow]

#: Simulated seconds per wall second. The tests judge windows of simulated time, whose estimate is the same at 2x and
#: 3x (the nodes keep up: every sample of the window is in it), and 3x takes a third less time; the killed
#: simulator's estimates turn invalid 0.59 s after the kill at either speed. The recursive mode runs at 2x: its first
#: window check comes after as many wall seconds at any speed.
SPEED = "speed:=3.0"


def _errors(document: dict, truth: dict) -> dict[str, float]:
    out = {}
    for group, key in (("segments", "static_moment_kgm"), ("joints", "coulomb_nm")):
        for owner, quantities in document[group].items():
            true = truth[group][owner][key]
            out[f"{owner}/{key}"] = abs(quantities[key]["value"] - true) / true
    return out


def _z_scores(document: dict, truth: dict) -> dict[str, float]:
    out = {}
    for group, key in (("segments", "static_moment_kgm"), ("joints", "coulomb_nm")):
        for owner, quantities in document[group].items():
            q = quantities[key]
            out[f"{owner}/{key}"] = (q["value"] - truth[group][owner][key]) / q["std"]
    return out


MakeCell = Callable[..., LiveCell]


@pytest.fixture
def cell(ros_domains: Callable[[], int]) -> Iterator[MakeCell]:
    cells: list[LiveCell] = []

    def make(offset: int, simulator_params: list[str], identifier_params: list[str] | None = None) -> LiveCell:
        cells.append(LiveCell(ros_domains(), simulator_params, identifier_params))
        return cells[-1]

    yield make
    for c in cells:
        c.close()


def _valid(c: LiveCell) -> bool:
    latest = c.latest()
    return latest is not None and latest["quality"]["valid"]


def _latest(c: LiveCell) -> dict[str, Any]:
    document = c.latest()
    assert document is not None, "no estimate arrived"
    return document


def _is_stale(document: dict[str, Any]) -> bool:
    """Whether an input went stale (the estimate says so by its code, whatever its text)."""
    return FindingCode.INPUT_STALE in [f.code for f in findings_of(document["quality"])]


def _window_span_s(document: dict | None) -> float:
    """Simulated seconds from an estimate's first sample to its last (0 before a window has samples)."""
    session = (document or {}).get("session") or {}
    if session.get("start_time_ns") is None or session.get("end_time_ns") is None:
        return 0.0
    return (session["end_time_ns"] - session["start_time_ns"]) / 1e9


def _spin_simulated_s(c: LiveCell, simulated_s: float, timeout_s: float = 60.0) -> bool:
    """Spin until an estimate's window ends ``simulated_s`` later in the session than the latest one's does now."""
    end_ns = lambda: ((c.latest() or {}).get("session") or {}).get("end_time_ns") or 0  # noqa: E731
    until_ns = end_ns() + simulated_s * 1e9
    return c.spin_until(lambda: end_ns() >= until_ns, timeout_s)


def _valid_over_a_full_window(c: LiveCell, window_s: float) -> bool:
    """The latest estimate is valid and its window is full (its samples span ``window_s`` but for the last ones'
    spacing and the angle filter's edges, which leave about 0.5 s out)."""
    return _valid(c) and _window_span_s(c.latest()) >= window_s - 1.0


TARGET_PERCENT = 12.0  # untared, the simulated cell's forearm static moment has ~11 % std, the upper arm's ~4 %
HOLD_S = 2.0
#: How long the signal is watched after it came: simulated seconds (20 s of wall time at 3x).
AFTER_SIGNAL_S = 60.0
LATCHED = QosSpec(reliable=True, depth=1, transient_local=True)


@dataclass
class PrecisionSignals:
    """What the ``precision`` identifier said: bsp/precision_reached (monotonic time, value) and its health."""

    signals: list[tuple[float, bool]] = field(default_factory=list)
    health: list[dict[str, str]] = field(default_factory=list)


@pytest.fixture(scope="class")
def seed_4_cell() -> Iterator[tuple[LiveCell, PrecisionSignals]]:
    """One session at 3x (seed 4) for two identifiers: a 60 s window (``bsp_identifier``) and the default 30 s one
    with a precision target (``precision``), whose latched signal and health are heard from its start."""
    heard = PrecisionSignals()

    def on_diagnostics(msg: Any) -> None:
        for status in read_diagnostic_array(msg).status:
            if status.name == "bsp_identifier":
                heard.health.append(dict(status.values))

    def subscribe(c: LiveCell) -> None:
        reached = c.topic_of("precision", "bsp/precision_reached")
        c.client.subscribe(
            "std_msgs/msg/Bool", reached, lambda m: heard.signals.append((time.monotonic(), m.data)), LATCHED
        )
        diagnostics = c.topic_of("precision", "/diagnostics")
        c.client.subscribe("diagnostic_msgs/msg/DiagnosticArray", diagnostics, on_diagnostics, "default")

    precision = [f"target_std_percent:={TARGET_PERCENT}", f"precision_hold_s:={HOLD_S}"]
    c = LiveCell(next_domain_id(), [SPEED, "seed:=4"], ["window_s:=60.0"], {"precision": precision}, subscribe)
    yield c, heard
    c.close()


class TestSeed4Session:
    """The windowed estimate over a full window, and the precision signal, from one simulated session."""

    def test_windowed_estimate_converges_to_the_truth(self, seed_4_cell: tuple[LiveCell, PrecisionSignals]) -> None:
        # A 60 s window: the core tolerances (0.5% on static moments) are set for sessions of minutes, and the
        # hand's static moment from 30 s scatters by about that much.
        c, _ = seed_4_cell
        assert c.spin_until(lambda: _valid(c), 60), c.latest()
        assert c.spin_until(lambda: _valid_over_a_full_window(c, 60.0), 60), c.latest()  # 60 s of simulated time
        valid = [d for _, d in c.estimates if d["quality"]["valid"]]
        assert len(valid) > 40
        document = valid[-1]
        errors = _errors(document, c.truth)
        print("relative errors", errors, "z", _z_scores(document, c.truth))
        for name, error in errors.items():
            assert error < (0.005 if "static_moment" in name else 0.10), (name, error)

    def test_precision_reached_comes_once_after_the_hold_and_stays(
        self, seed_4_cell: tuple[LiveCell, PrecisionSignals]
    ) -> None:
        # bsp/precision_reached turns true once, after the hold, latched for a late subscriber, and stays; the
        # estimates and /diagnostics say the same, and the std it promised holds for the rest of the session.
        c, heard = seed_4_cell
        signals = heard.signals
        assert c.spin_until(lambda: any(reached for _, reached in signals), 90), c.estimates_of["precision"][-1:]
        came_at = next(t for t, reached in signals if reached)
        # And afterwards, for 60 s of the session (20 s at 3x): no second message, every estimate still says reached.
        estimates = c.estimates_of["precision"]
        signal_end_ns = _window_end_ns(next(d for t, d in reversed(estimates) if t <= came_at))
        stayed = lambda: _window_end_ns(estimates[-1][1]) >= signal_end_ns + AFTER_SIGNAL_S * 1e9  # noqa: E731
        assert c.spin_until(stayed, 35), (estimates[-1][1].get("session"), signal_end_ns)
        assert [reached for _, reached in signals] == [False, True]
        with Client("late_subscriber", c.domain) as late:  # latched: session logic starting later reads it
            seen: list[bool] = []
            topic = c.topic_of("precision", "bsp/precision_reached")
            late.subscribe("std_msgs/msg/Bool", topic, lambda m: seen.append(m.data), LATCHED)
            assert late.spin_until(lambda: bool(seen), 10) and seen == [True]
        documents = list(estimates)
        assert documents and all("precision" in d for _, d in documents)
        first = next(i for i, (_, d) in enumerate(documents) if d["precision"]["reached"])
        assert all(d["precision"]["reached"] for _, d in documents[first:])
        # Before it came, the estimates within target held for HOLD_S: valid, each static moment within 12 %.
        within = [(t, d) for t, d in documents[:first] if d["precision"]["within_s"] is not None]
        assert within and documents[first][0] - within[0][0] >= HOLD_S - 0.3
        # Within target while it held and for the rest of the session: every estimate valid, its std as promised.
        after = [d for _, d in documents[first:]]
        span_s = (_window_end_ns(after[-1]) - _window_end_ns(after[0])) / 1e9
        # 5 Hz over 20 s of wall time: 100 estimates, some fewer where the machine is busy.
        assert len(after) >= 60 and span_s >= AFTER_SIGNAL_S - 1.0, (len(after), span_s)
        for document in [d for _, d in within] + after:
            assert document["quality"]["valid"], document["quality"]
            for parameter in document["precision"]["parameters"]:
                assert parameter["relative_std_percent"] <= TARGET_PERCENT, parameter
                std = document["segments"][parameter["owner"]]["static_moment_kgm"]
                assert 100 * std["std"] / abs(std["value"]) == pytest.approx(parameter["relative_std_percent"])
        print(
            "largest relative std after the signal, %:",
            max(p["relative_std_percent"] for d in after for p in d["precision"]["parameters"]),
        )
        assert abs(documents[first][0] - came_at) < 1.0
        health = heard.health
        assert health[-1]["precision.reached"] == "true" and float(health[-1]["precision.reached_after_s"]) >= HOLD_S


def _window_end_ns(document: dict[str, Any]) -> int:
    """Where an estimate's window ends in the session (its last sample's stamp, ns; 0 before it has samples)."""
    return int(((document.get("session") or {}).get("end_time_ns")) or 0)


def test_killed_simulator_turns_estimates_invalid_within_three_periods_and_restart_recovers(cell: MakeCell) -> None:
    c = cell(1, [SPEED, "seed:=5"])

    def steadily_valid() -> bool:  # early windows may still flip on excitation: kill a settled estimate
        return len(c.estimates) >= 10 and all(d["quality"]["valid"] for _, d in c.estimates[-10:])

    assert c.spin_until(steadily_valid, 90), c.latest()
    killed_at = time.monotonic()
    c.kill("cell_simulator")
    assert c.spin_until(lambda: _is_stale(_latest(c)), 10), c.latest()
    after = [(t, d) for t, d in c.estimates if t > killed_at]
    invalid_at = next(t for t, d in after if not d["quality"]["valid"])
    assert invalid_at - killed_at <= 3 * 0.2 + 0.15, invalid_at - killed_at  # 3 periods at 5 Hz, + delivery
    stale_at = next(t for t, d in after if _is_stale(d))
    assert stale_at - killed_at <= 3 * 0.2 + 0.15, stale_at - killed_at
    assert not any(d["quality"]["valid"] for t, d in after if t >= invalid_at)
    c.start("cell_simulator", [SPEED, "seed:=6"])
    assert c.spin_until(lambda: _valid(c), 60), c.latest()


def test_nan_bursts_and_a_backwards_clock_jump_never_poison_a_valid_estimate(cell: MakeCell) -> None:
    params = [
        SPEED,
        "seed:=7",
        "nan_burst_period_s:=7.0",
        "nan_burst_s:=0.3",
        "clock_jump_at_s:=40.0",
        "clock_jump_s:=20.0",
    ]
    c = cell(2, params)
    # Until the window refilled after the jump: up to then it could hold samples of both sides of the jump (the
    # 20 s of stamps the clock ran through twice); the windows after hold none from before.
    after_jump = lambda: _after_backwards_jump(c.estimates)  # noqa: E731
    refilled = lambda: any(d["quality"]["valid"] and _window_span_s(d) >= 29.0 for d in after_jump())  # noqa: E731
    assert c.spin_until(refilled, 80), [d["quality"]["message"] for d in after_jump()[-5:]]
    valid = [d for _, d in c.estimates if d["quality"]["valid"]]
    assert len(valid) > 20
    for document in valid:
        # Early windows are short and less precise: a poisoned estimate is off by far more than its std.
        for name, z in _z_scores(document, c.truth).items():
            assert abs(z) < 5, (name, z, document["quality"])
    refused = [d["session"]["refused_samples"]["wrench_non_finite"] for d in valid if "session" in d]
    assert max(refused) > 0  # the NaN bursts were seen and refused


def _after_backwards_jump(estimates: Estimates) -> list[dict]:
    """The estimates from the first whose window ends more than 5 s before an earlier one's (the clock jumped
    back), none if it has not."""
    latest_end_ns = None
    for k, (_, document) in enumerate(estimates):
        end_ns = ((document.get("session") or {}).get("end_time_ns")) if _window_span_s(document) else None
        if end_ns is None:
            continue
        if latest_end_ns is not None and end_ns < latest_end_ns - 5e9:
            return [d for _, d in estimates[k:]]
        latest_end_ns = end_ns if latest_end_ns is None else max(latest_end_ns, end_ns)
    return []


def test_one_marker_frame_jumping_0_67_m_leaves_the_live_estimate_right(cell: MakeCell) -> None:
    # The adversarial case of a swapped elbow marker: one frame 0.67 m off once made the live windows report
    # an elbow Coulomb of <= 0.035 Nm (truth 0.28) as valid. Here the jump is at 20 s of simulated time, and
    # every valid window holding it must stay right.
    jump_at_s = 20.0
    c = cell(6, [SPEED, "seed:=4", f"marker_jump_at_s:={jump_at_s}"], ["window_s:=60.0"])
    rejected: list[int] = []

    def on_diagnostics(msg: Any) -> None:
        for status in read_diagnostic_array(msg).status:
            if status.name == "joint_angle_estimator":
                rejected.append(int(dict(status.values)["rejected_frames"]))

    c.client.subscribe("diagnostic_msgs/msg/DiagnosticArray", "/diagnostics", on_diagnostics, "default")
    # Windows before, across and after the jump, until one spans 60 s of simulated time (the jump inside it).
    assert c.spin_until(lambda: _valid_over_a_full_window(c, 60.0), 90), c.latest()
    assert rejected and rejected[-1] >= 1, rejected  # the jump reached the estimator and was set aside
    start_ns = c.truth["start_time_ns"]
    holding = [d for _, d in c.estimates if d["quality"]["valid"] and _window_end_s(d, start_ns) > jump_at_s + 1.0]
    assert len(holding) > 20, [d["quality"]["message"] for _, d in c.estimates[-5:]]
    for document in holding:
        for name, z in _z_scores(document, c.truth).items():
            assert abs(z) < 5, (name, z, _window_end_s(document, start_ns))
    for name, error in _errors(holding[-1], c.truth).items():
        assert error < (0.005 if "static_moment" in name else 0.10), (name, error)


def _window_end_s(document: dict, start_ns: int) -> float:
    return (document["session"]["end_time_ns"] - start_ns) / 1e9


ROTATED_RPY_DEG = (90.0, -20.0, 135.0)
#: A control is judged by its first estimate whose window ends this far into the session (simulated seconds): past
#: its first checks, the windows long enough for a right rotation to give a valid estimate.
CONTROL_SESSION_S = 24.0


def _control_estimate(c: LiveCell, identifier: str) -> dict[str, Any]:
    """The first estimate of the further identifier ``identifier`` whose window ends ``CONTROL_SESSION_S`` into the
    session (spinning until it comes)."""

    def judged() -> dict[str, Any] | None:
        start_ns = c.truth.get("start_time_ns")
        for _, document in c.estimates_of[identifier]:
            end_ns = (document.get("session") or {}).get("end_time_ns")
            if start_ns is not None and end_ns is not None and end_ns - start_ns >= CONTROL_SESSION_S * 1e9:
                return document
        return None

    assert c.spin_until(lambda: judged() is not None, 60), c.estimates_of[identifier][-1:]
    document = judged()
    assert document is not None
    return document


@pytest.fixture(scope="class")
def rotated_sensor_cell() -> Iterator[LiveCell]:
    """A rotated sensor, identified without tf from one session twice: with its quaternion as the parameter
    (``bsp_identifier``) and, for the control, with the identity quaternion (``unrotated``). The parameter is
    forced: by default the simulator's TransformStamped would give each identifier the right rotation."""
    simulator = [SPEED, "seed:=8", "sensor_roll_pitch_yaw_deg:=[{}, {}, {}]".format(*ROTATED_RPY_DEG)]
    identifier = [wrench_frame_parameter(ROTATED_RPY_DEG), "wrench_frame_source:=parameter"]
    control = [wrench_frame_parameter((0.0, 0.0, 0.0)), "wrench_frame_source:=parameter"]
    c = LiveCell(next_domain_id(), simulator, identifier, {"unrotated": control})
    yield c
    c.close()


class TestRotatedSensorWithoutTf:
    """Where tf2_msgs is not installed (the PyPI wheels), the wrench frame's rotation is a parameter."""

    def test_a_rotated_sensor_without_tf_is_identified_with_the_quaternion_parameter(
        self, rotated_sensor_cell: LiveCell
    ) -> None:
        c = rotated_sensor_cell
        assert c.spin_until(lambda: _valid(c), 60), c.latest()
        assert _spin_simulated_s(c, 20.0), c.latest()  # a settled estimate, 20 s of session later
        document = c.latest()
        assert document is not None and document["quality"]["valid"], document
        for name, error in _errors(document, c.truth).items():
            assert error < (0.02 if "static_moment" in name else 0.25), (name, error)

    def test_a_rotated_sensor_taken_as_unrotated_gives_a_wrong_or_invalid_estimate(
        self, rotated_sensor_cell: LiveCell
    ) -> None:
        # The control of the test above: the same session with the identity quaternion is not estimated right.
        c = rotated_sensor_cell
        document = _control_estimate(c, "unrotated")
        wrong = not document["quality"]["valid"] or max(_errors(document, c.truth).values()) > 0.05
        assert wrong, document["quality"]


@pytest.fixture(scope="class")
def turning_sensor_cell() -> Iterator[LiveCell]:
    """A sensor on the robot's flange, turning with the handle, its transform published as TransformStamped (the
    PyPI wheels have no tf2_msgs); one session identified twice: rotating each wrench at its own stamp by the topic
    (``bsp_identifier``) and, for the control, with one fixed rotation for every wrench (``fixed``)."""
    simulator = [SPEED, "seed:=10", "sensor_turns:=true", "transform_topic:=ft_sensor/transform"]
    c = LiveCell(
        next_domain_id(), simulator, ["wrench_frame_source:=topic"], {"fixed": ["wrench_frame_source:=parameter"]}
    )
    yield c
    c.close()


class TestTurningSensor:
    """The sensor turns with the handle: each wrench is rotated at its own stamp."""

    def test_a_turning_sensor_with_its_transform_on_a_topic_is_identified_right(
        self, turning_sensor_cell: LiveCell
    ) -> None:
        c = turning_sensor_cell
        assert c.spin_until(lambda: _valid(c), 60), c.latest()
        assert _spin_simulated_s(c, 20.0), c.latest()  # a settled estimate, 20 s of session later
        document = c.latest()
        assert document is not None and document["quality"]["valid"], document
        for name, z in _z_scores(document, c.truth).items():
            assert abs(z) < 3, (name, z)
        for name, error in _errors(document, c.truth).items():
            assert error < (0.02 if "static_moment" in name else 0.25), (name, error)

    def test_a_turning_sensor_taken_as_fixed_is_not_valid_and_right(self, turning_sensor_cell: LiveCell) -> None:
        # The control of the test above: the same session with one fixed rotation (its mean) for every wrench.
        c = turning_sensor_cell
        document = _control_estimate(c, "fixed")
        right = document["quality"]["valid"] and max(abs(z) for z in _z_scores(document, c.truth).values()) < 3
        assert not right, document["quality"]


SUPPORT_FRACTION = 0.5


@dataclass
class WeightSupport:
    """What was heard of the windowed identifier's weight support: (monotonic time, wrench) and the joint states'
    angles by stamp."""

    supports: list[tuple[float, Any]] = field(default_factory=list)
    angles: dict[int, np.ndarray] = field(default_factory=dict)


@pytest.fixture(scope="class")
def seed_9_cell() -> Iterator[tuple[LiveCell, WeightSupport]]:
    """One session at 2x (seed 9) for two identifiers: windowed with weight support (``bsp_identifier``) and in the
    recursive mode (``recursive``); the weight support and the joint states are heard from the start."""
    heard = WeightSupport()

    def keep(msg: Any) -> None:
        sample = read_joint_state(msg)
        heard.angles[sample.t_ns] = sample.position

    def subscribe(c: LiveCell) -> None:
        on_support = lambda m: heard.supports.append((time.monotonic(), read_wrench_stamped(m)))  # noqa: E731
        c.client.subscribe("geometry_msgs/msg/WrenchStamped", "bsp/weight_support", on_support)
        c.client.subscribe("sensor_msgs/msg/JointState", "arm/joint_states", keep, "estimates")

    support = [f"support_fraction:={SUPPORT_FRACTION}"]
    c = LiveCell(next_domain_id(), ["speed:=2.0", "seed:=9"], support, {"recursive": ["mode:=recursive"]}, subscribe)
    yield c, heard
    c.close()


class TestSeed9Session:
    """The weight support of the windowed estimate, and the recursive mode's estimate, from one simulated session."""

    def test_weight_support_carries_the_share_of_the_true_gravity_torques_only_after_a_valid_estimate(
        self, seed_9_cell: tuple[LiveCell, WeightSupport]
    ) -> None:
        # bsp/weight_support: J(q)^T F = s tau_G(q) of the simulated arm, only while valid.
        c, heard = seed_9_cell
        supports, angles = heard.supports, heard.angles
        assert c.spin_until(lambda: len(supports) > 200, 90), (len(supports), c.latest())
        first_valid = next(t for t, d in c.estimates if d["quality"]["valid"])
        assert supports[0][0] >= first_valid - 0.05  # nothing before the first valid estimate
        truth = c.truth
        beta = np.array([truth["segments"][s]["static_moment_kgm"] for s in ("upper_arm", "forearm", "hand")])
        lengths = np.array([truth["segments"][s]["length_m"] for s in ("upper_arm", "forearm", "hand")])
        checked = 0
        for _, sample in supports[200 - 100 : 200]:  # the last 100 of the first 200, wherever the test runs
            assert sample.frame_id == "world"
            q = angles.get(sample.t_ns)
            if q is None:
                continue
            wrench_yzx = np.array([sample.force_n[1], sample.force_n[2], sample.torque_nm[0]])
            carried = contact_jacobian(q[None, :], lengths)[0].T @ wrench_yzx
            wanted = SUPPORT_FRACTION * gravity_regressor(q[None, :])[0] @ beta
            # The node uses its own estimate and marker-measured lengths: within a few percent of the truth.
            assert np.all(np.abs(carried - wanted) < 0.03 * np.abs(wanted) + 0.01), (q, carried, wanted)
            checked += 1
        assert checked > 20

    def test_recursive_mode_estimate_is_right_within_its_std(self, seed_9_cell: tuple[LiveCell, WeightSupport]) -> None:
        c, _ = seed_9_cell
        estimates = c.estimates_of["recursive"]
        valid_now = lambda: bool(estimates) and estimates[-1][1]["quality"]["valid"]  # noqa: E731
        assert c.spin_until(valid_now, 90), estimates[-1:]
        c.spin_until(lambda: False, 10)
        valid = [d for _, d in estimates if d["quality"]["valid"]]
        document = valid[-1]
        print("recursive: relative errors", _errors(document, c.truth), "z", _z_scores(document, c.truth))
        # Every parameter (before the recursive filter took its direction of motion from fits centred on the joint
        # states, its Coulomb terms lagged at reversals: shoulder z 4.9-5.2 in this test).
        for name, z in _z_scores(document, c.truth).items():
            assert abs(z) < 3, (name, z)


def test_the_robot_handle_pose_stands_for_a_misplaced_hand_marker_live(cell: MakeCell) -> None:
    # The hand marker on the back of the hand, 25 mm off the bearing's centre (offline this makes the estimate
    # invalid or wrong, test_robot_contact.py); the robot publishes the contact point on /robot/handle_pose.
    simulator = [SPEED, "seed:=12", "robot_handle_pose:=true", "hand_marker_offset_mm:=[0.0, 25.0]"]
    c = cell(8, simulator)
    assert c.spin_until(lambda: _valid(c), 60), c.latest()
    assert _spin_simulated_s(c, 20.0), c.latest()  # a settled estimate, 20 s of session later
    document = _latest(c)
    assert document["quality"]["valid"], document["quality"]
    assert document["quality"]["contact_point"] == "robot_handle_pose"
    for name, z in _z_scores(document, c.truth).items():
        assert abs(z) < 3, (name, z)
    # The hand's length runs from the wrist marker to the robot's contact point, not to the skin marker 25 mm off.
    length = document["segments"]["hand"]["length_m"]["value"]
    assert abs(length - c.truth["segments"]["hand"]["length_m"]) < 0.003, length
