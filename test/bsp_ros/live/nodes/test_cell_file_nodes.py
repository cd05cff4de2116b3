"""The nodes and the cell file: a bad one refused naming the value; a simulator whose sensor is mounted otherwise than
the identifier's cell file says so once on /diagnostics, naming what to set, and the received transform is used."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from node_processes import NodeProcesses, Peer, domain_id

from bsp_ros.live.runtime.ros import has_message
from msg_adapters.diagnostics import read_diagnostic_array

pytestmark = [pytest.mark.dds]


@pytest.mark.parametrize("name", ["bsp_identifier", "cell_simulator", "joint_angle_estimator"])
def test_a_bad_cell_file_is_refused_naming_the_value(name: str, tmp_path: Path) -> None:
    cell = tmp_path / "cell.yaml"
    cell.write_text("schema: bsp_ros/cell/1\nft_sensor:\n  rotation_xyzw: [0.0, 0.0, 0.0, 2.0]\n")
    nodes = NodeProcesses(domain_id(), tmp_path)
    out = subprocess.run(
        [sys.executable, "-m", f"bsp_ros.live.nodes.{name}", "--ros-args", "-p", f"cell_file:={cell}"],
        env=nodes.env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert out.returncode == 2, out.stderr
    assert "cell_file" in out.stderr and "ft_sensor.rotation_xyzw [0.0, 0.0, 0.0, 2.0] has norm 2" in out.stderr
    assert "Traceback" not in out.stderr


def test_a_sensor_mounted_off_the_cell_file_is_said_once_and_its_transform_used(tmp_path: Path) -> None:
    domain = domain_id()
    nodes, peer = NodeProcesses(domain, tmp_path), Peer(domain)
    health: list[dict[str, str]] = []

    def on_diagnostics(msg: Any) -> None:
        health.extend(dict(s.values) for s in read_diagnostic_array(msg).status if s.name == "bsp_identifier")

    try:
        peer.client.subscribe("diagnostic_msgs/msg/DiagnosticArray", "/diagnostics", on_diagnostics, "default")
        nodes.start("bsp_identifier", [])  # the shipped cell: yaw 30 deg
        nodes.start("cell_simulator", ["sensor_roll_pitch_yaw_deg:=[180.0, 0.0, 45.0]"])  # re-mounted: 15 deg off
        key = "wrench_frame.ft_sensor.disagrees"
        assert peer.spin_until(lambda: bool(health) and key in health[-1], 30), health[-1:]
        peer.spin_until(lambda: False, 1.0)
    finally:
        nodes.close()
        peer.close()
    notice = health[-1][key]
    assert "15.0 deg off the stated rotation wrench_frame_rotation_xyzw" in notice and "the transform is used" in notice
    assert "ft_sensor.rotation_xyzw" in notice  # the cell file's key to set
    assert health[-1]["wrench_frame.ft_sensor"] == ("tf" if has_message("tf2_msgs/msg/TFMessage") else "topic")
    assert nodes.log("bsp_identifier").count("15.0 deg off the stated rotation") == 1  # once in the log
