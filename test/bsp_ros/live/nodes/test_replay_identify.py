"""A bag played at real time into the live nodes gives the estimate `identify_bag` gives offline."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import pytest
from live_cell import wrench_frame_parameter
from node_processes import NodeProcesses, Peer, domain_id

from bsp_ros.bag import write_session_bag
from bsp_ros.bag.offline import identify_bag
from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.simulation import human_arm_cell, simulate_cell

pytestmark = [pytest.mark.dds, pytest.mark.slow]

# Live and offline agree to 0.013 % on 30 s of this session and to 0.011 % on 20 s (over DDS): the agreement does
# not hang on the length, and 20 s replay in a third less time.
DURATION_S = 20.0
SEED = 4  # a well excited session: offline standard errors are below 0.3 % on every quantity
TOLERANCE = 0.01  # relative, on every static moment and Coulomb amplitude
QUANTITIES = (("segments", "static_moment_kgm"), ("joints", "coulomb_nm"))


class LiveOfflineMismatchError(AssertionError):
    """The live estimate and the offline one differ by more than TOLERANCE."""


def _values(document: dict[str, Any]) -> dict[str, float]:
    return {
        f"{owner}/{key}": float(quantities[key]["value"])
        for group, key in QUANTITIES
        for owner, quantities in document[group].items()
    }


def _is_valid(document: dict[str, Any]) -> bool:
    return bool(document["quality"]["valid"])


def _is_stale(document: dict[str, Any]) -> bool:
    """Whether an input went stale (the estimate says so by its code, whatever its text)."""
    return FindingCode.INPUT_STALE in [f.code for f in findings_of(document["quality"])]


def _settled_stale(estimates: list[tuple[float, dict[str, Any]]], after: float, quiet_s: float = 1.0) -> bool:
    """Every estimate of the last ``quiet_s`` (all after ``after``) is stale: the replay's inputs are over.

    A single stale estimate is not enough: a starved identifier process can publish one before it drains
    its queue of inputs.
    """
    now = time.monotonic()
    if now - after < quiet_s:
        return False
    recent = [d for t, d in estimates if t > now - quiet_s]
    return len(recent) >= 3 and all(not _is_valid(d) and _is_stale(d) for d in recent)


# Live vs offline on this bag (seed 4, 30 s), in process without DDS: wrist Coulomb -1.5 %, hand static moment
# +0.3 %, every other quantity within 0.1 %; over DDS the same. The live path gives already filtered angles to
# kinematics_from_angles(angle_filter=False), whose direction-velocity noise estimate (raw minus filtered angles)
# is then exactly 0, so the 4-sigma deadband around turning points shrinks to its 10 %-of-speed floor and the slow
# wrist keeps rows whose direction of motion is ambiguous. With the offline noise injected, live and offline agree
# within 0.17 % (measured over DDS too).
def test_real_time_replay_into_the_nodes_matches_the_offline_identification(tmp_path: Path) -> None:
    simulated = simulate_cell(human_arm_cell(seed=SEED, duration_s=DURATION_S))
    bag = write_session_bag(tmp_path / "session", simulated.session)
    offline = identify_bag(bag)
    assert offline["quality"]["valid"], offline["quality"]

    domain = domain_id(0)
    nodes = NodeProcesses(domain, tmp_path)
    peer = Peer(domain)
    player = None
    try:
        estimates = peer.listen_json("bsp/estimate_json")
        nodes.start("joint_angle_estimator", [])
        # The window holds the whole bag; after the replay the estimate of all of it stays valid for stale_s.
        # Without tf2_msgs /tf_static is not played: the sensor's rotation is given as a parameter.
        frame = wrench_frame_parameter(tuple(human_arm_cell().sensor.roll_pitch_yaw_deg))
        nodes.start("bsp_identifier", [f"window_s:={DURATION_S + 20}", "stale_s:=1.0", frame])
        # `bsp play` waits until every topic of the bag has a subscriber (the nodes are up) before playing.
        player = nodes.play(bag, "--rate", 1, "--wait-subscribers", 30)
        assert peer.spin_until(lambda: player.poll() is not None, DURATION_S + 40), nodes.log("bsp_identifier")
        output = player.communicate()[0]
        assert player.returncode == 0, output
        ended = time.monotonic()
        assert peer.spin_until(lambda: _settled_stale(estimates, ended), 15), estimates[-1][1]["quality"]
    finally:
        if player is not None and player.poll() is None:
            player.kill()
            player.wait(5)
        nodes.close()
        peer.close()

    n_wrench = simulated.session.wrench.t_ns.size
    assert f"/ft_sensor/wrench: {n_wrench} published (bag lists {n_wrench})" in output, output
    valid = [d for _, d in estimates if _is_valid(d)]
    assert len(valid) > 10, [d["quality"]["message"] for _, d in estimates]
    live = valid[-1]
    # The final window spans the bag, from its first wrench sample to its last. Its start is 0-0.4 s late when
    # the nodes' own topics match after the replay began (seen under load); the 2.2 s allow for a late match,
    # not for the 1 s steps lost while the identifier waited for the segment lengths (3 s seen in CI, fixed).
    live_session, offline_session = live["session"], offline["session"]
    assert live_session["start_time_ns"] - offline_session["start_time_ns"] < 2.2e9, (live_session, offline_session)
    assert offline_session["end_time_ns"] - live_session["end_time_ns"] < 0.1e9, (live_session, offline_session)
    expected, got = _values(offline), _values(live)
    assert set(got) == set(expected)
    errors = {name: (got[name] - value) / abs(value) for name, value in expected.items()}
    summary = {name: f"{100 * error:+.3f} %" for name, error in errors.items()}
    print("live vs offline:", summary, "samples", live["quality"]["n_samples"], offline["quality"]["n_samples"])
    worst = max(errors, key=lambda name: abs(errors[name]))
    if abs(errors[worst]) >= TOLERANCE:
        raise LiveOfflineMismatchError(f"{worst}: live {got[worst]:.6g}, offline {expected[worst]:.6g}; all: {summary}")
