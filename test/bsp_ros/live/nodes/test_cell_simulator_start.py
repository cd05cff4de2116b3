"""cell_simulator starts its session when it is listened to: no burst of past samples, nothing lost at the start."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from typing import Any

import numpy as np
import pytest
from node_processes import ROOT

from bsp_ros.live.runtime.ros import Client
from msg_adapters.wrench import read_wrench_stamped


@pytest.mark.dds
def test_the_session_starts_with_its_first_subscriber_and_loses_no_sample(ros_domain: int) -> None:
    node = subprocess.Popen(
        [sys.executable, "-m", "bsp_ros.live.nodes.cell_simulator", "--ros-args", "-p", "wait_for_subscribers:=1"],
        env={
            **os.environ,
            "ROS_DOMAIN_ID": str(ros_domain),
            "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
        },
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    client = Client("start_listener", ros_domain)
    try:
        time.sleep(3.0)  # the node is up and waiting: without the wait, these 3 s of samples would be lost
        subscribed_ns = time.time_ns()
        wrenches: list[Any] = []
        truth: dict[str, Any] = {}
        client.subscribe("geometry_msgs/msg/WrenchStamped", "/ft_sensor/wrench", wrenches.append, "sensor_input")
        client.subscribe("std_msgs/msg/String", "sim/truth", lambda m: truth.update(json.loads(m.data)), "tf_static")
        assert client.spin_until(lambda: bool(truth) and len(wrenches) >= 200, 30), (len(wrenches), truth.keys())
    finally:
        node.kill()
        node.wait(5)
        client.close()
    start_ns = truth["start_time_ns"]
    assert truth["simulation"]["start_ns"] == start_ns  # the trajectory's t = 0 on the stamps' clock
    assert start_ns >= subscribed_ns  # the session waited for its subscriber
    t_ns = np.array([read_wrench_stamped(m).t_ns for m in wrenches])
    period_ns = 1e9 / truth["simulation"]["wrench_hz"]
    # Every sample from the start on arrived, in order: the first within a period of the start, no gap after it.
    assert t_ns[0] - start_ns < period_ns
    assert (np.diff(t_ns) > 0).all() and np.diff(t_ns).max() < 1.5 * period_ns
