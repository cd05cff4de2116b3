"""What the identifier says of its wrench frame: a rotation that never came, a transform off the stated one."""

from __future__ import annotations

import numpy as np

from bsp_ros.cell import read_cell_file
from bsp_ros.core.simulation import rotation_from_rpy_deg
from bsp_ros.live.online.frame_notices import FrameNotices, stated_rotation
from bsp_ros.live.online.frames import WrenchFrames
from bsp_ros.live.runtime.cell_parameters import IDENTIFIER_FROM_CELL, SIMULATOR_FROM_CELL, with_cell_defaults
from bsp_ros.live.runtime.parameters import Param
from msg_adapters.rotation import quaternion_from_matrix
from msg_adapters.tf import TransformSample

CELL = read_cell_file()
STATED = stated_rotation(CELL.rotation_xyzw, CELL)


def _frames() -> WrenchFrames:
    return WrenchFrames("world", use_tf=True, parameter_rotation=CELL.rotation_world_from_sensor, tf_wait_s=2.0)


def test_the_stated_rotation_names_the_cell_file_or_the_parameter() -> None:
    assert STATED == f"wrench_frame_rotation_xyzw (cell file {CELL.source}: ft_sensor.rotation_xyzw)"
    assert stated_rotation((0.0, 0.0, 0.0, 1.0), CELL) == "parameter wrench_frame_rotation_xyzw"


def test_a_missing_transform_is_said_once_and_stays_on_diagnostics() -> None:
    frames, notices = _frames(), FrameNotices("topic /ft_sensor/transform (TransformStamped)", STATED)
    assert frames.rotation_for("ft_sensor", 0) is None
    assert notices.new_lines(frames) == []  # still waiting
    np.testing.assert_allclose(frames.rotation_for("ft_sensor", 2_000_000_001), CELL.rotation_world_from_sensor)
    (line,) = notices.new_lines(frames)
    assert "no transform world -> ft_sensor from topic /ft_sensor/transform" in line
    assert "ft_sensor.rotation_xyzw" in line and "wrench_frame_rotation_xyzw" in line
    assert notices.new_lines(frames) == []  # once
    assert list(notices.diagnostics(frames)) == ["wrench_frame.ft_sensor.missing"]


def test_a_transform_off_the_cell_by_more_than_a_degree_is_said_once_naming_what_to_set() -> None:
    frames, notices = _frames(), FrameNotices("tf (/tf_static, /tf)", STATED)
    mounted = rotation_from_rpy_deg(180.0, 0.0, 40.0)  # the sensor turned by 10 deg since the cell file was written
    frames.on_transforms([TransformSample(0, "world", "ft_sensor", np.zeros(3), quaternion_from_matrix(mounted))])
    np.testing.assert_allclose(frames.rotation_for("ft_sensor", 0), mounted, atol=1e-12)  # the transform is used
    (line,) = notices.new_lines(frames)
    assert "10.0 deg off the stated rotation wrench_frame_rotation_xyzw" in line and "the transform is used" in line
    assert notices.new_lines(frames) == []
    assert set(notices.diagnostics(frames)) == {"wrench_frame.ft_sensor.disagrees"}
    # The same rotation as the cell: nothing to say.
    agreeing, quiet = _frames(), FrameNotices("tf (/tf_static, /tf)", STATED)
    sample = TransformSample(0, "world", "ft_sensor", np.zeros(3), np.asarray(CELL.rotation_xyzw))
    agreeing.on_transforms([sample])
    assert agreeing.rotation_for("ft_sensor", 0) is not None
    assert quiet.new_lines(agreeing) == [] and quiet.diagnostics(agreeing) == {}


def test_the_cell_gives_the_defaults_of_the_parameters_it_names() -> None:
    table = (
        Param(name="world_frame", default="world", description=""),
        Param(name="wrench_frame_rotation_xyzw", default=[0.0, 0.0, 0.0, 1.0], description=""),
        Param(name="tare_file", default="x", description=""),
        Param(name="window_s", default=30.0, description="", unit="s", lo=1.0),
    )
    merged = {p.name: p for p in with_cell_defaults(table, CELL, IDENTIFIER_FROM_CELL)}
    assert merged["wrench_frame_rotation_xyzw"].default == list(CELL.rotation_xyzw)
    assert merged["tare_file"].default == "" and merged["world_frame"].default == "world"
    assert merged["window_s"] == table[3]  # not the cell's: as it was
    simulator = {
        p.name: p
        for p in with_cell_defaults(
            (Param(name="sensor_roll_pitch_yaw_deg", default=[0.0] * 3, description=""),), CELL, SIMULATOR_FROM_CELL
        )
    }
    np.testing.assert_allclose(simulator["sensor_roll_pitch_yaw_deg"].default, (180.0, 0.0, 30.0), atol=1e-6)
