"""`bsp demo` tells a newcomer what runs, that the warm-up is expected, and whether it worked."""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import pytest

from bsp_ros.cli import build_parser
from bsp_ros.cli.demo import NODES, VERDICT_STATIC_PERCENT, introduction, node_arguments, render, state_line, verdict
from bsp_ros.core import simulation as sim
from bsp_ros.core.estimate_schema import Estimate

ROOT = Path(__file__).resolve().parents[3]


def _demo_parser() -> argparse.ArgumentParser:
    subparsers = next(a for a in build_parser()._actions if a.dest == "command")
    return subparsers.choices["demo"]  # type: ignore[index]


def test_help_describes_the_demo_and_every_option() -> None:
    parser = _demo_parser()
    assert parser.description and "simulated" in parser.description and "verdict" in parser.description
    for action in parser._actions:
        if action.option_strings and action.dest != "help":
            assert action.help, action.option_strings


def _truth() -> dict:
    return sim.simulate_cell(sim.human_arm_cell(seed=0, duration_s=5.0)).truth.to_dict()


def _estimate(truth: dict, valid: bool = True, scale: float = 1.0, message: str = "identified") -> Estimate:
    """An estimate as read from a document of the shape bsp/estimate_json carries, off the truth by ``scale``."""
    segments = {
        name: {"static_moment_kgm": {"value": scale * q["static_moment_kgm"], "std": 1e-4, "source": "data"}}
        for name, q in truth["segments"].items()
    }
    joints = {
        name: {"coulomb_nm": {"value": q["coulomb_nm"], "std": 1e-3, "source": "data"}}
        for name, q in truth["joints"].items()
    }
    return Estimate.from_json({"segments": segments, "joints": joints, "quality": {"valid": valid, "message": message}})


def test_the_verdict_is_ok_for_a_valid_estimate_near_the_truth_and_says_what_the_numbers_mean() -> None:
    truth = _truth()
    worked, text = verdict(_estimate(truth, scale=1.001), truth)
    assert worked
    assert text.startswith("verdict: OK") and "within 0.1 % of the simulated truth" in text
    assert "static moment (kg m)" in text and "Coulomb (Nm)" in text


def test_the_verdict_fails_when_the_estimate_is_far_off_invalid_or_missing() -> None:
    truth = _truth()
    off = 1 + 1.5 * VERDICT_STATIC_PERCENT / 100
    worked, text = verdict(_estimate(truth, scale=off), truth)
    assert not worked and text.startswith("verdict: FAILED") and f"+{100 * (off - 1):.2f} %" in text
    worked, text = verdict(_estimate(truth, valid=False, message="the shoulder moved in one direction"), truth)
    assert not worked and "the shoulder moved in one direction" in text
    worked, text = verdict(None, truth)
    assert not worked and "no estimate arrived" in text


def test_an_invalid_estimate_during_the_warm_up_is_called_expected_and_later_invalid() -> None:
    truth = _truth()
    estimate = _estimate(truth, valid=False, message="the wrist moved in one direction only")
    assert state_line(estimate, warming_up=True).startswith("warming up (expected")
    assert state_line(estimate, warming_up=False).startswith("INVALID: the wrist moved")
    assert "warming up (expected" in render(estimate, truth, 10.0, warming_up=True)


def test_the_introduction_names_the_processes_and_the_middleware() -> None:
    args = _demo_parser().parse_args(["--duration", "30"])
    text = introduction(args, "rmw_fastrtps_cpp", 42)
    for word in ("simulated", "cell_simulator", "joint_angle_estimator", "bsp_identifier", "rclpy"):
        assert word in text
    assert "rmw_fastrtps_cpp" in text and "domain 42" in text and "50 % of the arm's weight" in text
    assert "cell description bsp_ros/config/cell.yaml" in text
    assert max(len(line) for line in text.splitlines()) <= 110


def test_every_node_reads_the_shipped_cell_and_no_rotation_is_passed_by_hand() -> None:
    """The demo starts its nodes as a real cell does: with the cell file, whose mounting the simulator publishes as
    its transform and the identifier takes where none comes."""
    from bsp_ros.cell import SHIPPED_CELL, angle_between_deg, read_cell_file
    from bsp_ros.live.nodes.bsp_identifier import PARAMETERS as IDENTIFIER
    from bsp_ros.live.nodes.cell_simulator import PARAMETERS as SIMULATOR
    from bsp_ros.live.online.frames import rotation_from_quaternion_xyzw
    from bsp_ros.live.runtime.cell_parameters import IDENTIFIER_FROM_CELL, SIMULATOR_FROM_CELL, with_cell_defaults

    for subject in ("human", "paper-arm"):
        lines = node_arguments(_demo_parser().parse_args(["--subject", subject]))
        assert set(lines) == set(NODES)
        for name, line in lines.items():
            assert f"cell_file:={SHIPPED_CELL}" in line, name
            assert not [a for a in line if "rotation" in a or "frame" in a], (name, line)
    cell = read_cell_file(SHIPPED_CELL)
    simulator = {p.name: p.default for p in with_cell_defaults(SIMULATOR, cell, SIMULATOR_FROM_CELL)}
    identifier = {p.name: p.default for p in with_cell_defaults(IDENTIFIER, cell, IDENTIFIER_FROM_CELL)}
    mounted = sim.rotation_from_rpy_deg(*simulator["sensor_roll_pitch_yaw_deg"])
    stated = rotation_from_quaternion_xyzw(identifier["wrench_frame_rotation_xyzw"])
    assert angle_between_deg(mounted, stated) < 1e-6
    assert simulator["transform_topic"] == identifier["wrench_frame_topic"] == cell.transform_topic


@pytest.mark.dds
@pytest.mark.slow
def test_a_short_demo_run_ends_with_a_verdict(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    # 15 s at 4x: 60 s of the simulated session, the identifier's 30 s window full for about half of it (the
    # final estimate's static moments came within 0.2-0.4 % of the truth at 3x and 4x; the verdict allows 2 %).
    done = subprocess.run(
        [sys.executable, "-m", "bsp_ros.cli", "demo", "--duration", "15", "--speed", "4"],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.stdout.startswith("bsp demo: a simulated rehabilitation cell")
    assert "verdict: OK" in done.stdout, done.stdout[-2000:] + done.stderr[-2000:]
    assert done.returncode == 0
