"""The cell description: the shipped file describes the simulated cell; a bad value is named, each on its own."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from bsp_ros.cell import SHIPPED_CELL, CellDescription, angle_between_deg, read_cell_file
from bsp_ros.core.simulation import human_arm_cell, rotation_from_rpy_deg
from bsp_ros.errors import InputError

GOOD = """\
schema: bsp_ros/cell/1
world_frame: lab
ft_sensor:
  frame: ati_mini45
  wrench_topic: /ati/wrench
  roll_pitch_yaw_deg: [90.0, -20.0, 135.0]
  transform_topic: /robot/flange
  tare_file: today.tare.yaml
markers:
  topic_prefix: /vicon/
contact_point:
  handle_pose_topic: ""
emg:
  envelope_topic: /delsys/envelopes
"""


def test_the_shipped_cell_is_the_simulated_cell() -> None:
    cell = read_cell_file()
    simulated = human_arm_cell()
    assert cell.source == str(SHIPPED_CELL)
    assert cell.sensor_frame == simulated.sensor.frame_id and cell.world_frame == "world"
    # The simulator's default mounting, within a micro-degree (the file holds 12 digits).
    assert angle_between_deg(cell.rotation_world_from_sensor, simulated.sensor.rotation_world_from_sensor) < 1e-6
    np.testing.assert_allclose(cell.roll_pitch_yaw_deg, simulated.sensor.roll_pitch_yaw_deg, atol=1e-6)
    assert (cell.wrench_topic, cell.transform_topic) == ("/ft_sensor/wrench", "/ft_sensor/transform")
    assert cell.marker_topic("elbow") == "/mocap/elbow" and cell.handle_pose_topic == "/robot/handle_pose"
    assert cell.emg_topic == "/emg/envelope"
    assert cell.tare_file is None


def test_a_cell_file_in_roll_pitch_yaw_with_a_relative_tare(tmp_path: Path) -> None:
    (tmp_path / "today.tare.yaml").write_text("{}")
    (tmp_path / "cell.yaml").write_text(GOOD)
    cell = read_cell_file(tmp_path / "cell.yaml")
    expected = rotation_from_rpy_deg(90.0, -20.0, 135.0)  # tf2's setRPY, as the simulator mounts its sensor
    assert angle_between_deg(cell.rotation_world_from_sensor, expected) < 1e-9
    np.testing.assert_allclose(cell.roll_pitch_yaw_deg, (90.0, -20.0, 135.0), atol=1e-9)
    assert cell.rotation_xyzw[3] >= 0.0 and abs(np.linalg.norm(cell.rotation_xyzw) - 1.0) < 1e-12
    assert cell.tare_file == tmp_path / "today.tare.yaml"
    assert (cell.world_frame, cell.sensor_frame, cell.wrench_topic) == ("lab", "ati_mini45", "/ati/wrench")
    assert (cell.transform_topic, cell.marker_topic("hand"), cell.handle_pose_topic) == (
        "/robot/flange",
        "/vicon/hand",
        "",
    )
    assert cell.emg_topic == "/delsys/envelopes"


def test_the_angle_between_two_rotations() -> None:
    a = rotation_from_rpy_deg(180.0, 0.0, 30.0)
    assert angle_between_deg(a, a) == pytest.approx(0.0, abs=1e-6)
    assert angle_between_deg(a, rotation_from_rpy_deg(180.0, 0.0, 33.0)) == pytest.approx(3.0)
    assert angle_between_deg(np.eye(3), rotation_from_rpy_deg(0.0, 0.0, 180.0)) == pytest.approx(180.0)


@pytest.mark.parametrize(
    ("edit", "needles"),
    [
        ({"world_frame": "/world"}, ["world_frame must be a frame name", "'/world'"]),
        ({"frame": "world"}, ["ft_sensor.frame must differ from world_frame"]),
        ({"wrench_topic": "ft sensor"}, ["ft_sensor.wrench_topic must be a ROS topic name", "'ft sensor'"]),
        ({"rotation_xyzw": "[0.0, 0.0, 0.0, 2.0]"}, ["ft_sensor.rotation_xyzw [0.0, 0.0, 0.0, 2.0] has norm 2"]),
        ({"rotation_xyzw": "[0.0, 0.0, 1.0]"}, ["ft_sensor.rotation_xyzw must be 4 finite numbers"]),
        ({"rotation_xyzw": "[.nan, 0.0, 0.0, 1.0]"}, ["ft_sensor.rotation_xyzw must be 4 finite numbers"]),
        ({"topic_prefix": "/mocap"}, ["markers.topic_prefix must be a topic prefix ending in /", "'/mocap'"]),
        ({"tare_file": "missing.yaml"}, ["ft_sensor.tare_file", "missing.yaml is not a file"]),
        # Two bad values: both named, in one line.
        ({"wrench_topic": "a b", "transform_topic": "c d"}, ["wrench_topic", "'a b'", "transform_topic", "'c d'"]),
    ],
)
def test_each_bad_value_is_named_in_one_line(edit: dict[str, str], needles: list[str], tmp_path: Path) -> None:
    lines = {
        "world_frame": "world",
        "frame": "ft_sensor",
        "wrench_topic": "/ft_sensor/wrench",
        "rotation_xyzw": "[0.0, 0.0, 0.0, 1.0]",
        "transform_topic": "/ft_sensor/transform",
        "tare_file": '""',
        "topic_prefix": "/mocap/",
    }
    lines.update(edit)
    text = (
        f"schema: bsp_ros/cell/1\nworld_frame: {lines['world_frame']}\nft_sensor:\n"
        f"  frame: {lines['frame']}\n  wrench_topic: {lines['wrench_topic']}\n"
        f"  rotation_xyzw: {lines['rotation_xyzw']}\n  transform_topic: {lines['transform_topic']}\n"
        f"  tare_file: {lines['tare_file']}\nmarkers:\n  topic_prefix: {lines['topic_prefix']}\n"
    )
    path = tmp_path / "cell.yaml"
    path.write_text(text)
    with pytest.raises(InputError) as caught:
        read_cell_file(path)
    message = str(caught.value)
    assert "\n" not in message and message.startswith(f"cell file {path}: ")
    for needle in needles:
        assert needle in message, (needle, message)


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("schema: bsp_ros/cell/2\n", "schema must be bsp_ros/cell/1, got 'bsp_ros/cell/2'"),
        ("schema: bsp_ros/cell/1\nft_sensor:\n  rotation_xzyw: [0, 0, 0, 1]\n", "unknown key(s) rotation_xzyw"),
        ("schema: bsp_ros/cell/1\nwrld_frame: world\n", "unknown key(s) wrld_frame"),
        ("schema: bsp_ros/cell/1\nft_sensor: [1, 2]\n", "ft_sensor must be a mapping"),
        ("schema: bsp_ros/cell/1\nemg:\n  topic: /emg\n", "unknown key(s) topic in emg (known: envelope_topic)"),
        ("schema: bsp_ros/cell/1\nemg:\n  envelope_topic: emg envelope\n", "emg.envelope_topic must be a ROS topic"),
        ("- 1\n", "expected a mapping"),
        ("a: [\n", "not YAML"),
        (
            "schema: bsp_ros/cell/1\nft_sensor:\n  rotation_xyzw: [0, 0, 0, 1]\n  roll_pitch_yaw_deg: [0, 0, 0]\n",
            "not both",
        ),
    ],
)
def test_a_file_that_is_no_cell_description_is_refused_naming_why(text: str, needle: str, tmp_path: Path) -> None:
    path = tmp_path / "cell.yaml"
    path.write_text(text)
    with pytest.raises(InputError, match="cell file") as caught:
        read_cell_file(path)
    assert needle in str(caught.value)


def test_a_missing_cell_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"cell file .*nope\.yaml: no such file"):
        read_cell_file(tmp_path / "nope.yaml")


def test_a_description_is_frozen() -> None:
    cell = CellDescription()
    with pytest.raises(AttributeError):
        cell.world_frame = "lab"  # type: ignore[misc]
