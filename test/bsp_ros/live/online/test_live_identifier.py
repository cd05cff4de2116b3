"""bsp_identifier's inputs and updates without rclpy (LiveIdentifier and its two modes): the windowed mode publishes
what its window estimates, the recursive mode its filter per sample, the wrench delay shifts the stamps, and a failed
update is an invalid estimate."""

from __future__ import annotations

import json

import numpy as np
import pytest

from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.methods import LiveMode
from bsp_ros.live.online.identifier_modes import ModeEstimate
from bsp_ros.live.online.identifier_settings import IdentifierSettings
from bsp_ros.live.online.live_identifier import LiveIdentifier
from bsp_ros.live.online.windowed import WindowConfig, WindowedIdentifier
from msg_adapters.joint_state import JointStateSample
from msg_adapters.wrench import WrenchSample

FRAME = "ft_sensor"


def _identifier(log_error=pytest.fail, **values) -> LiveIdentifier[ModeEstimate]:
    """A LiveIdentifier whose updates are the modes' estimates as they are (no messages)."""
    return LiveIdentifier(IdentifierSettings.from_parameters(values), lambda estimate: estimate, log_error)


def _document(estimate: ModeEstimate) -> dict:
    return json.loads(json.dumps(estimate.estimate.to_json(), allow_nan=False))


def _feed(identifier: LiveIdentifier, streams, until_s: float) -> list:
    """The first ``until_s`` of ``streams`` into ``identifier`` as the node hands them (world = the sensor's axes);
    returns the passive moments published per sample."""
    _, stamps, wrench, states, raw = streams
    end = int(stamps[0]) + int(until_s * 1e9)
    identifier.add_lengths(raw[0][2])
    passive, w, s = [], 0, 0
    for t_ns, q_rad, _ in raw:
        if t_ns > end:
            break
        while w < len(stamps) and stamps[w] <= t_ns:
            f_y, f_z, m_x = wrench[w]
            identifier.received("wrench", t_ns)
            sample = WrenchSample(int(stamps[w]), FRAME, np.array([0.0, f_y, f_z]), np.array([m_x, 0.0, 0.0]))
            out = identifier.add_wrench(sample, np.eye(3))
            passive += [out] if out is not None else []
            w += 1
        while s < len(states) and states[s][0] <= t_ns:
            state = states[s][1]
            identifier.add_joint_state(
                JointStateSample(states[s][0], "", (), state.q_rad, state.velocity_rad_s, np.zeros(0)), t_ns
            )
            s += 1
        identifier.add_raw_angles(t_ns, q_rad, t_ns)
    return passive


def test_the_windowed_mode_publishes_its_windows_estimate(live_streams) -> None:
    identifier = _identifier(window_s=20.0)
    assert _document(identifier.update(0))["quality"]["findings"][0]["code"] == "input_waiting"
    assert identifier.update_times() == {}  # a quick verdict is not timed
    passive = _feed(identifier, live_streams, 25.0)
    now = identifier.mode.window.wrench.last_t_ns
    estimate = identifier.update(now)
    document = _document(estimate)
    assert document["mode"] == "windowed" and document["quality"]["valid"], document["quality"]["message"]
    assert estimate.estimate.mode is LiveMode.WINDOWED
    assert passive == [] and estimate.with_passive  # the windowed passive moments go out with each estimate
    assert estimate.stamp_ns == now  # stamped with the window's newest wrench
    assert set(identifier.update_times()) == {
        "update_ms_mean",
        "update_ms_max",
        "update_cpu_ms_mean",
        "update_cpu_ms_max",
    }
    # The same as its window identified directly (the node's settings: its passive model, no elastic fallback).
    options = IdentifierSettings.from_parameters({}).options
    direct = WindowedIdentifier(3, WindowConfig(20.0, 60.0, options))
    t_a, rows = identifier.mode.window.angles.since(0)
    for t, row in zip(t_a, rows, strict=True):
        direct.add_joint_state(int(t), row[:3], row[3:])
    t_w, yzx = identifier.mode.window.wrench.since(0)
    for t, row in zip(t_w, yzx, strict=True):
        direct.add_wrench(int(t), row)
    expected = direct.estimate(orientation=(FRAME, np.eye(3))).estimate.with_mode(LiveMode.WINDOWED)
    assert document == json.loads(json.dumps(expected.to_json()))
    assert document["quality"]["timing"] == {"wrench_delay_s": 0.0, "wrench_delay_std_s": 0.0, "source": "none"}
    counters = identifier.counters()
    assert counters["wrench"] > 0 and counters["joint_states"] > 0 and "wrench_spikes" not in counters


def test_the_recursive_mode_publishes_its_passive_moments_per_sample(live_streams) -> None:
    identifier = _identifier(mode="recursive")
    passive = _feed(identifier, live_streams, 15.0)
    assert passive and passive[-1].names == identifier.mode.feed.passive_joints  # type: ignore[attr-defined]
    estimate = identifier.update(identifier.mode.window.wrench.last_t_ns)
    document = _document(estimate)
    assert document["mode"] == "recursive" and "timing" not in document["quality"] and not estimate.with_passive
    assert estimate.estimate.mode is LiveMode.RECURSIVE and estimate.estimate.method == "recursive"
    counters = identifier.counters()
    assert counters["raw_angles"] > 0 and counters["joint_states"] > 0 and "wrench_spikes" in counters
    assert identifier.update_times()  # the filter's update is timed
    # A new contact point restarts: the window is empty and the next estimate waits for it.
    assert identifier.set_contact_from_robot(True) and not identifier.set_contact_from_robot(True)
    assert identifier.mode.window.wrench.last_t_ns is None


def test_a_known_wrench_delay_shifts_every_wrench_stamp_back(live_streams) -> None:
    identifier = _identifier(wrench_delay_s=0.01)
    sample = WrenchSample(2_000_000_000, FRAME, np.zeros(3), np.zeros(3))
    identifier.add_wrench(sample, np.eye(3))
    assert identifier.mode.window.wrench.last_t_ns == 1_990_000_000


def test_an_update_that_fails_is_published_invalid_and_logged(live_streams) -> None:
    logged: list[str] = []
    identifier = _identifier(logged.append)
    _feed(identifier, live_streams, 12.0)

    def broken(window):
        raise RuntimeError("broken")

    identifier.mode.window.estimator.estimate_window = broken  # type: ignore[method-assign]
    document = _document(identifier.update(identifier.mode.window.wrench.last_t_ns))
    assert not document["quality"]["valid"] and document["mode"] == "windowed"
    assert [f.code for f in findings_of(document["quality"])] == [FindingCode.INTERNAL_ERROR]
    assert document["quality"]["message"] == "internal error: RuntimeError('broken')"
    assert logged and "RuntimeError: broken" in logged[0]
