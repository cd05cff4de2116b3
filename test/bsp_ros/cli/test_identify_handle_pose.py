"""`bsp identify` on a bag with the robot's handle pose: it stands for the hand marker, and the estimate says so."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.bag import read_session, write_session_bag
from bsp_ros.cli import main
from bsp_ros.core import simulation as sim


@pytest.fixture(scope="module")
def robot_bag(tmp_path_factory) -> tuple[Path, sim.SimulatedSession]:
    spec = dataclasses.replace(sim.human_arm_cell(seed=9, duration_s=60.0), robot_handle_pose=True)
    simulated = sim.simulate_cell(spec)
    # A cell with no marker on the hand at all: the robot's pose is the contact point.
    markers = {k: v for k, v in simulated.session.markers.items() if k != "hand"}
    session = dataclasses.replace(simulated.session, markers=markers)
    bag = write_session_bag(tmp_path_factory.mktemp("bags") / "robot", session, simulated.truth.to_dict())
    return bag, simulated


def test_the_handle_pose_survives_the_bag(robot_bag) -> None:
    bag, simulated = robot_bag
    read = read_session(bag)
    pose, written = read.session.handle_pose, simulated.session.handle_pose
    assert pose is not None and written is not None
    assert np.array_equal(pose.t_ns, written.t_ns)
    assert np.array_equal(pose.position_m, written.position_m)
    assert "hand" not in read.session.markers
    assert read.report.topics["/robot/handle_pose"].read == written.t_ns.size


def test_identify_takes_the_contact_point_from_the_robot(robot_bag, tmp_path) -> None:
    bag, simulated = robot_bag
    out = tmp_path / "e.json"
    assert main(["identify", str(bag), "--json", str(out), "--format", "none"]) == 0
    estimate = json.loads(out.read_text())
    assert estimate["quality"]["valid"], estimate["quality"]["message"]
    assert estimate["quality"]["contact_point"] == "robot_handle_pose"
    truth = simulated.truth.to_dict()["segments"]
    for segment, quantities in estimate["segments"].items():
        for key in ("length_m", "static_moment_kgm"):
            q = quantities[key]
            assert abs(q["value"] - truth[segment][key]) <= 3 * q["std"], (segment, key)


def test_without_the_handle_pose_topic_the_missing_hand_marker_is_named(robot_bag, capsys) -> None:
    bag, _ = robot_bag
    assert main(["identify", str(bag), "--handle-pose-topic", "", "--format", "none"]) == 13
    assert "/mocap/hand" in capsys.readouterr().err
