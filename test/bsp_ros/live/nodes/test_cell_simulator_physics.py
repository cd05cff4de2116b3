"""cell_simulator delegates its physics to the core: a turning, filtered sensor and re-placed skin markers live."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from typing import Any

import numpy as np
import pytest
from node_processes import ROOT

from bsp_ros.core import simulation as sim
from bsp_ros.live.runtime.ros import Client
from msg_adapters.wrench import read_wrench_stamped


def _core_simulator(truth: dict[str, Any]) -> sim.CellSimulator:
    """The core's simulator of the cell the node describes in its truth (no noise: the noise-free reading)."""
    known = sim.SessionTruth.from_dict(truth)
    block = truth["simulation"]
    sensor = sim.SensorSpec(
        wrench_hz=block["wrench_hz"],
        roll_pitch_yaw_deg=tuple(block["sensor_roll_pitch_yaw_deg"]),
        turns_with_handle=block["sensor_turns_with_handle"],
        filter_delay_s=block["wrench_filter_delay_s"],
        filter_kind=block["wrench_filter_kind"],
        clock_offset_s=block["wrench_clock_offset_s"],
    )
    markers = sim.MarkerSpec(skin_offset_m=tuple(tuple(pair) for pair in block["skin_offset_m"]))
    spec = sim.CellSpec(
        subject=known.subject,
        passive=known.passive,
        trajectory=known.trajectory,
        sensor=sensor,
        markers=markers,
        duration_s=block["duration_s"],
        start_ns=block["start_ns"],
        inertia=block["inertia"],
    )
    return sim.CellSimulator(spec)


@pytest.mark.dds
def test_the_node_publishes_the_cores_turning_filtered_wrench_and_records_it(ros_domain: int) -> None:
    client = Client("physics_listener", ros_domain)
    wrenches: list[Any] = []
    truth: dict[str, Any] = {}
    client.subscribe("geometry_msgs/msg/WrenchStamped", "/ft_sensor/wrench", wrenches.append, "sensor_data")
    client.subscribe("std_msgs/msg/String", "sim/truth", lambda m: truth.update(json.loads(m.data)), "tf_static")
    params = ["seed:=3", "speed:=5.0", "sensor_turns:=true", "wrench_filter_delay_s:=0.02", "skin_offset_mm:=5.0"]
    node = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "bsp_ros.live.nodes.cell_simulator",
            "--ros-args",
            *[a for p in params for a in ("-p", p)],
        ],
        env={
            **os.environ,
            "ROS_DOMAIN_ID": str(ros_domain),
            "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
        },
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        assert client.spin_until(lambda: bool(truth) and len(wrenches) > 2000, 60), (len(wrenches), truth.keys())
    finally:
        node.kill()
        node.wait(5)
        client.close()
    block = truth["simulation"]
    assert block["inertia"] is True and block["sensor_turns_with_handle"] is True
    assert block["wrench_delay_s"] == pytest.approx(0.02) and block["skin_offset_bound_m"] == 0.005
    assert 0.0 < np.abs(block["skin_offset_m"]).max() <= 0.005
    samples = [read_wrench_stamped(m) for m in wrenches]
    t_ns = np.array([s.t_ns for s in samples])
    force = np.array([s.force_n for s in samples])
    core = _core_simulator(truth)
    t_s = core.seconds_since_start(t_ns)
    predicted, _ = core.filtered_reading(t_s)
    assert np.abs(force - predicted).max() < 6 * block["force_noise_n"]  # the node's noise only
    # The sensor did turn: read as fixed at its mounting, the prediction would miss by far more than the noise.
    fixed = core.wrench_world(t_s)[:, :2] @ core.rotation_world_from_sensor[1:, :]
    assert np.abs(force - fixed).max() > 0.5 and np.ptp(np.degrees(core.handle_pitch_rad(t_s))) > 2.0
