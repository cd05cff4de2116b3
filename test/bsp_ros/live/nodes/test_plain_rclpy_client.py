"""A cell's own plain-rclpy nodes (no bsp_ros code) feed the bsp_ros nodes and read /bsp/estimate."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from node_processes import NodeProcesses

pytestmark = [pytest.mark.dds, pytest.mark.slow]

SCRIPT = Path(__file__).with_name("plain_rclpy_cell.py")


def test_an_independent_rclpy_cell_gets_its_arm_identified(ros_domain: int, tmp_path: Path) -> None:
    nodes = NodeProcesses(ros_domain, tmp_path)
    try:
        nodes.start("joint_angle_estimator", [])
        nodes.start("bsp_identifier", [])
        # The script imports rclpy, numpy and message packages only (it checks so itself).
        env = {k: v for k, v in nodes.env.items() if k != "PYTHONPATH"}
        out = subprocess.run(
            [sys.executable, str(SCRIPT), "--timeout", "150"],
            env=env,
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=200,
        )
    finally:
        nodes.close()
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert result["valid"], (result, nodes.log("bsp_identifier"))
    for segment, true in result["truth"].items():  # the script's own check, restated for the report
        assert abs(result["estimate"][segment] - true) < max(4 * result["std"][segment], 0.02 * true), result
    assert not result["bsp_ros_imported"]
    assert out.returncode == 0, out.stderr
