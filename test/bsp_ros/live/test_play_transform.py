"""`bsp play` without tf2_msgs: a bag's /tf_static goes out as the cell's sensor rotation on its TransformStamped
topic (what bsp_identifier reads), said once; a rotation the bag cannot give is what the nodes need: exit 1."""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from ros_domains import next_domain_id

from bsp_ros.bag import write_session_bag
from bsp_ros.cell import angle_between_deg
from bsp_ros.core.simulation import human_arm_cell, rotation_from_rpy_deg, simulate_cell
from bsp_ros.live.runtime.ros import Client, has_message
from msg_adapters.rotation import matrix_from_quaternion
from msg_adapters.tf import read_transform_stamped

pytestmark = [
    pytest.mark.dds,
    pytest.mark.skipif(has_message("tf2_msgs/msg/TFMessage"), reason="tf2_msgs is installed: /tf_static plays as is"),
]

ROOT = Path(__file__).resolve().parents[3]
PEER = Path(__file__).with_name("play_record_peer.py")
MOUNTED = rotation_from_rpy_deg(90.0, -20.0, 135.0)


def _bag(tmp_path: Path, frame_id: str) -> Path:
    spec = human_arm_cell(duration_s=6.0)
    session = simulate_cell(replace(spec, sensor=replace(spec.sensor, roll_pitch_yaw_deg=(90.0, -20.0, 135.0)))).session
    session = replace(session, wrench=replace(session.wrench, frame_id=frame_id))
    return write_session_bag(tmp_path / f"bag_{frame_id}", session)


def _subscribe_to_the_played_topics(client: Client) -> None:
    """Subscribe (and drop what comes) to every topic the bag plays on, so that `bsp play` starts as soon as they
    have matched, not at the end of its wait for subscribers."""
    client.subscribe("geometry_msgs/msg/WrenchStamped", "/ft_sensor/wrench", lambda _: None, "sensor_input")
    for marker in ("shoulder", "elbow", "wrist", "hand"):
        client.subscribe("geometry_msgs/msg/PoseStamped", f"/mocap/{marker}", lambda _: None, "sensor_input")


def _play(bag: Path, domain: int) -> subprocess.Popen[str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    args = ["play", str(bag), "--rate", "0", "--domain", str(domain), "--wait-subscribers", "10"]
    return subprocess.Popen(
        [sys.executable, str(PEER), *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env
    )


def test_tf_static_goes_out_as_the_sensor_rotation_on_the_transform_topic(tmp_path: Path) -> None:
    bag = _bag(tmp_path, "ft_sensor")
    domain = next_domain_id()
    received: list[Any] = []
    with Client("transform_listener", domain) as client:
        client.subscribe("geometry_msgs/msg/TransformStamped", "/ft_sensor/transform", received.append, "tf")
        _subscribe_to_the_played_topics(client)
        player = _play(bag, domain)
        client.spin_until(lambda: bool(received) or player.poll() is not None, 30)
        out, err = player.communicate(timeout=30)
    assert player.returncode == 0, out + err
    assert received, out + err
    sample = read_transform_stamped(received[0])
    assert (sample.parent_frame, sample.child_frame) == ("world", "ft_sensor")
    assert angle_between_deg(matrix_from_quaternion(sample.rotation_xyzw), MOUNTED) < 1e-6
    text = out + err
    assert text.count("tf2_msgs is not installed") == 1, text  # said once
    assert "/ft_sensor/transform" in text and "pip install" not in text and "skipped" not in text, text


def test_a_bag_whose_tf_misses_the_cell_s_sensor_frame_exits_1_naming_it(tmp_path: Path) -> None:
    bag = _bag(tmp_path, "ati_sensor")  # the cell file says ft_sensor
    domain = next_domain_id()
    with Client("transform_listener", domain) as client:
        client.subscribe("geometry_msgs/msg/TransformStamped", "/ft_sensor/transform", lambda _: None, "tf")
        _subscribe_to_the_played_topics(client)
        player = _play(bag, domain)
        client.spin_until(lambda: player.poll() is not None, 60)
        out, err = player.communicate(timeout=60)
    assert player.returncode == 1, out + err
    assert "not played, though the nodes need it: the sensor's rotation" in err
    assert "world -> ft_sensor" in err and "pip install" not in out + err
    np.testing.assert_equal(err.count("bsp play: warning"), 1)
