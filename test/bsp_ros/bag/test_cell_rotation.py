"""The sensor's rotation of a bag without /tf_static: from its TransformStamped topic, from the cell's mounting
`bsp record` wrote into its metadata, or from `bsp identify --cell`; a cell that disagrees with a recorded rotation
is named."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.bag import read_session, write_session_bag
from bsp_ros.bag.cell_metadata import custom_data_from_cell, stated_from_custom_data
from bsp_ros.bag.offline import identify_bag
from bsp_ros.cell import angle_between_deg, read_cell_file
from bsp_ros.cli import main
from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.simulation import human_arm_cell, rotation_from_rpy_deg, simulate_cell
from msg_adapters.rotation import quaternion_from_matrix
from msg_adapters.tf import TransformSample

CELL = read_cell_file()  # the shipped cell: the simulator's sensor mounting
# A sensor mounted otherwise than the shipped cell says, so that a rotation taken from the wrong place shows.
MOUNTED = rotation_from_rpy_deg(90.0, -20.0, 135.0)


@pytest.fixture(scope="module")
def session():
    spec = human_arm_cell(seed=4, duration_s=40.0)
    spec = replace(spec, sensor=replace(spec.sensor, roll_pitch_yaw_deg=(90.0, -20.0, 135.0)))
    return simulate_cell(spec).session


@pytest.fixture(scope="module")
def reference(session, tmp_path_factory) -> dict:
    """The estimate of the bag with /tf_static: the rotation every other way must give."""
    bag = write_session_bag(tmp_path_factory.mktemp("ref") / "with_tf_static", session)
    document = identify_bag(bag)
    assert document["quality"]["valid"] and document["bag"]["rotation_source"] == "tf", document["quality"]
    return document


def _static_moments(document: dict) -> dict[str, float]:
    return {s: q["static_moment_kgm"]["value"] for s, q in document["segments"].items()}


def test_the_transform_topic_gives_the_rotation_without_tf_static(session, reference, tmp_path: Path) -> None:
    t0 = int(session.wrench.t_ns[0])
    samples = [
        TransformSample(t0 + k * 1_000_000_000, "world", "ft_sensor", np.zeros(3), quaternion_from_matrix(MOUNTED))
        for k in range(40)
    ]
    bag = write_session_bag(tmp_path / "topic", session, tf_static=False, transform_samples=samples)
    read = read_session(bag)
    assert read.report.rotation_source == "topic"
    assert angle_between_deg(read.session.rotation_world_from_sensor, MOUNTED) < 1e-9
    document = identify_bag(bag)
    assert document["quality"]["valid"] and document["bag"]["rotation_source"] == "topic"
    assert _static_moments(document) == pytest.approx(_static_moments(reference), rel=1e-9)


def test_the_mounting_record_wrote_into_the_metadata_gives_the_rotation(session, reference, tmp_path: Path) -> None:
    cell = replace(CELL, rotation_xyzw=tuple(float(v) for v in quaternion_from_matrix(MOUNTED)))
    bag = write_session_bag(tmp_path / "meta", session, tf_static=False, custom_data=custom_data_from_cell(cell))
    document = identify_bag(bag)
    assert document["quality"]["valid"] and document["bag"]["rotation_source"] == "metadata"
    notes = [f.values["detail"] for f in findings_of(document["quality"]) if f.code is FindingCode.BAG_NOTE]
    assert any("the bag's metadata" in detail and "states" in detail for detail in notes), notes
    assert _static_moments(document) == pytest.approx(_static_moments(reference), rel=1e-6)


def test_without_a_recorded_rotation_identify_says_so_and_cell_gives_it(session, reference, tmp_path: Path) -> None:
    bag = write_session_bag(tmp_path / "bare", session, tf_static=False)
    code = main(["identify", str(bag), "--json", str(tmp_path / "bare.json"), "--format", "none"])
    bare = json.loads((tmp_path / "bare.json").read_text())
    assert code == 1 and bare["bag"]["rotation_source"] == "assumed"
    assert FindingCode.ROTATION_ASSUMED in {f.code for f in findings_of(bare["quality"])}

    cell_file = tmp_path / "cell.yaml"
    xyzw = [float(v) for v in quaternion_from_matrix(MOUNTED)]
    cell_file.write_text(f"schema: bsp_ros/cell/1\nft_sensor:\n  rotation_xyzw: {xyzw}\n")
    out = tmp_path / "cell.json"
    assert main(["identify", str(bag), "--cell", str(cell_file), "--json", str(out), "--format", "none"]) == 0
    given = json.loads(out.read_text())
    assert given["bag"]["rotation_source"] == "cell" and given["quality"]["valid"]
    assert _static_moments(given) == pytest.approx(_static_moments(reference), rel=1e-6)


def test_a_cell_off_the_recorded_rotation_is_named_and_the_recording_used(session, reference, tmp_path: Path) -> None:
    bag = write_session_bag(tmp_path / "recorded", session)
    off = quaternion_from_matrix(MOUNTED @ rotation_from_rpy_deg(0.0, 0.0, 10.0))  # re-mounted by 10 deg
    cell_file = tmp_path / "cell.yaml"
    cell_file.write_text(f"schema: bsp_ros/cell/1\nft_sensor:\n  rotation_xyzw: {[float(v) for v in off]}\n")
    out = tmp_path / "off.json"
    assert main(["identify", str(bag), "--cell", str(cell_file), "--json", str(out), "--format", "none"]) == 0
    document = json.loads(out.read_text())
    assert document["bag"]["rotation_source"] == "tf"
    notes = [f for f in findings_of(document["quality"]) if f.code == FindingCode.BAG_NOTE and "deg off" in f.text]
    assert len(notes) == 1 and "10.0 deg off" in notes[0].text and "ft_sensor.rotation_xyzw" in notes[0].text
    assert _static_moments(document) == pytest.approx(_static_moments(reference), rel=1e-9)


def test_metadata_that_states_no_usable_rotation_is_named_not_used() -> None:
    stated, problem = stated_from_custom_data({"bsp_ros.cell.rotation_xyzw": "[0, 0, 0, 3]"})
    assert stated is None and "not a unit quaternion" in problem
    assert stated_from_custom_data({}) == (None, "")
    stated, problem = stated_from_custom_data(custom_data_from_cell(CELL))
    assert problem == "" and stated is not None and stated.source == "metadata"
    assert stated.rotation_xyzw == pytest.approx(CELL.rotation_xyzw)
