"""`bsp tare` finds the sensor's orientation as `bsp identify` does: on a tare bag recorded without tf2_msgs (the cell's
TransformStamped topic in place of /tf, the mounting in metadata.yaml's custom_data), from `--cell FILE`, and says
where a cell disagrees with what was recorded."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from bsp_ros.bag import TopicMap, write_session_bag
from bsp_ros.bag.cell_metadata import custom_data_from_cell
from bsp_ros.bag.tare_reader import read_tare_bag
from bsp_ros.cell import CellDescription, angle_between_deg
from bsp_ros.cli import main
from bsp_ros.core.simulation import TareSpec, human_arm_cell, rotation_from_rpy_deg, simulate_tare
from bsp_ros.core.simulation.tare import SimulatedTare
from bsp_ros.core.streams import Session
from msg_adapters.rotation import quaternion_from_matrix
from msg_adapters.tf import TransformSample

# A sensor mounted otherwise than the shipped cell says, so that an orientation taken from the wrong place shows.
MOUNT_RPY_DEG = (90.0, -20.0, 135.0)
HANDLE_MASS_KG = 0.3
HANDLE_COM_M = (0.0, 0.02, 0.05)
FORCE_OFFSET_N = (3.0, -3.0, 3.0)


def _tare(swing_deg: float, duration_s: float) -> SimulatedTare:
    spec = human_arm_cell(seed=4, duration_s=60.0)
    sensor = replace(
        spec.sensor,
        roll_pitch_yaw_deg=MOUNT_RPY_DEG,
        force_bias_n=FORCE_OFFSET_N,
        handle_mass_kg=HANDLE_MASS_KG,
        handle_com_m=HANDLE_COM_M,
    )
    swinging = TareSpec(duration_s=duration_s, swing_rpy_deg=(swing_deg, swing_deg, swing_deg))
    return simulate_tare(replace(spec, sensor=sensor), swinging)


def _samples(tare: SimulatedTare) -> list[TransformSample]:
    """The swinging sensor's orientation as transforms of the sensor frame in world."""
    return [
        TransformSample(int(t), "world", tare.wrench.frame_id, np.zeros(3), quaternion_from_matrix(r))
        for t, r in zip(tare.tf_t_ns.tolist(), tare.rotations_world_from_sensor, strict=True)
    ]


def _session(tare: SimulatedTare) -> Session:
    return Session(wrench=tare.wrench, markers={}, rotation_world_from_sensor=tare.rotation_world_from_sensor)


def _cell_file(path: Path, rotation: np.ndarray, extra: str = "") -> Path:
    xyzw = [float(v) for v in quaternion_from_matrix(rotation)]
    path.write_text(f"schema: bsp_ros/cell/1\nft_sensor:\n  rotation_xyzw: {xyzw}\n{extra}")
    return path


def _tare_file(args: list[str]) -> dict:
    out = Path(args[args.index("--out") + 1])
    assert main(["tare", *args]) == 0
    return yaml.safe_load(out.read_text())


@pytest.fixture(scope="module")
def swing() -> SimulatedTare:
    return _tare(20.0, 20.0)


@pytest.fixture(scope="module")
def rest() -> SimulatedTare:
    return _tare(0.0, 10.0)


def test_a_swinging_tare_on_the_transform_topic_separates_the_handle_as_on_tf(swing, tmp_path: Path) -> None:
    session = _session(swing)
    on_tf = write_session_bag(tmp_path / "on_tf", session, tf_static=False, tf_samples=_samples(swing))
    on_topic = write_session_bag(tmp_path / "on_topic", session, tf_static=False, transform_samples=_samples(swing))
    read = read_tare_bag(on_topic)
    assert read.orientation_source == "topic" and read.rotations_world_from_sensor is not None
    np.testing.assert_allclose(read.rotations_world_from_sensor, read_tare_bag(on_tf).rotations_world_from_sensor)

    reference = _tare_file([str(on_tf), "--out", str(tmp_path / "tf.yaml")])
    doc = _tare_file([str(on_topic), "--out", str(tmp_path / "topic.yaml")])
    assert doc["load"] == "separated"
    mass = doc["payload"]["mass_kg"]
    assert abs(mass["value"] - HANDLE_MASS_KG) < 4 * mass["std"]
    np.testing.assert_allclose(doc["payload"]["com_m"]["value"], HANDLE_COM_M, atol=0.002)
    force = doc["force_offset_n"]
    assert np.all(np.abs(np.subtract(force["value"], swing.truth["force_offset_n"])) < 4 * np.array(force["std"]))
    assert mass["value"] == pytest.approx(reference["payload"]["mass_kg"]["value"], rel=1e-9)
    np.testing.assert_allclose(force["value"], reference["force_offset_n"]["value"], rtol=1e-9)


def test_a_tare_at_rest_takes_the_mounting_record_wrote_into_the_metadata(rest, tmp_path: Path, capsys) -> None:
    xyzw = quaternion_from_matrix(rest.rotation_world_from_sensor)
    mounted = CellDescription(rotation_xyzw=(float(xyzw[0]), float(xyzw[1]), float(xyzw[2]), float(xyzw[3])))
    session = _session(rest)
    bag = write_session_bag(tmp_path / "meta", session, tf_static=False, custom_data=custom_data_from_cell(mounted))
    read = read_tare_bag(bag)
    assert read.orientation_source == "metadata"
    assert angle_between_deg(read.rotations_world_from_sensor[0], rest.rotation_world_from_sensor) < 1e-6

    reference = _tare_file([str(write_session_bag(tmp_path / "static", session)), "--out", str(tmp_path / "s.yaml")])
    capsys.readouterr()
    doc = _tare_file([str(bag), "--out", str(tmp_path / "meta.yaml")])
    assert "sensor orientation from the mounting in the bag's metadata" in capsys.readouterr().out
    assert doc["load"] == "constant"
    recorded = doc["recording"]["rotation_world_from_sensor"]
    np.testing.assert_allclose(recorded, reference["recording"]["rotation_world_from_sensor"], atol=1e-9)
    np.testing.assert_allclose(doc["force_offset_n"]["value"], reference["force_offset_n"]["value"], rtol=1e-12)


def test_a_bare_tare_bag_says_its_orientation_is_unknown_and_cell_gives_it(rest, tmp_path: Path, capsys) -> None:
    bag = write_session_bag(tmp_path / "bare", _session(rest), tf_static=False)
    capsys.readouterr()
    doc = _tare_file([str(bag), "--out", str(tmp_path / "bare.yaml")])
    err = capsys.readouterr().err
    assert doc["recording"]["rotation_world_from_sensor"] is None
    assert "orientation is unknown" in err and "--cell FILE" in err

    cell = _cell_file(tmp_path / "cell.yaml", rest.rotation_world_from_sensor)
    doc = _tare_file([str(bag), "--cell", str(cell), "--out", str(tmp_path / "cell.yaml.tare")])
    out = capsys.readouterr()
    assert "sensor orientation from the --cell file's mounting" in out.out and str(cell) in out.err
    recorded = np.asarray(doc["recording"]["rotation_world_from_sensor"])
    assert angle_between_deg(recorded, rest.rotation_world_from_sensor) < 1e-6


def test_a_cell_off_the_recorded_rotation_is_named_and_the_recording_used(rest, tmp_path: Path, capsys) -> None:
    bag = write_session_bag(tmp_path / "static", _session(rest))
    off = rest.rotation_world_from_sensor @ rotation_from_rpy_deg(0.0, 0.0, 10.0)  # re-mounted by 10 deg
    cell = _cell_file(tmp_path / "cell.yaml", off)
    read = read_tare_bag(bag, _cell_topics(cell))
    assert read.orientation_source == "tf_static"
    (warning,) = [w for w in read.warnings if "deg off" in w]
    assert "10.0 deg off" in warning and "ft_sensor.rotation_xyzw" in warning
    assert angle_between_deg(read.rotations_world_from_sensor[0], rest.rotation_world_from_sensor) < 1e-9
    capsys.readouterr()
    _tare_file([str(bag), "--cell", str(cell), "--out", str(tmp_path / "t.yaml")])
    assert "10.0 deg off" in capsys.readouterr().err


def test_the_cell_names_the_wrench_topic_an_option_left_at_its_default(rest, tmp_path: Path) -> None:
    bag = write_session_bag(tmp_path / "renamed", _session(rest), topics=TopicMap(wrench="/cell_a/ft/wrench"))
    cell = _cell_file(tmp_path / "cell.yaml", rest.rotation_world_from_sensor, "  wrench_topic: /cell_a/ft/wrench\n")
    assert main(["tare", str(bag), "--out", str(tmp_path / "none.yaml")]) == 13  # /ft_sensor/wrench is not there
    doc = _tare_file([str(bag), "--cell", str(cell), "--out", str(tmp_path / "t.yaml")])
    assert doc["recording"]["n_samples"] == rest.wrench.t_ns.size
    # An option given still wins over the cell's name.
    assert main(["tare", str(bag), "--cell", str(cell), "--wrench-topic", "/x", "--out", str(tmp_path / "x")]) == 13


def _cell_topics(cell_file: Path) -> TopicMap:
    """The topics `bsp tare --cell FILE` reads with: the cell's names and the mounting it states."""
    from bsp_ros.bag.cell_metadata import topic_map_from_cell
    from bsp_ros.cell import read_cell_file

    return topic_map_from_cell(read_cell_file(cell_file))
