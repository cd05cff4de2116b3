"""`bsp sessions add`: session times that are not wall-clock, what users type for --time, pseudonymity, NaN."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import pytest
import yaml
from cli_run import bsp

from bsp_ros.bag.writer import write_session_bag
from bsp_ros.clinic.store import open_store
from bsp_ros.clinic.store.samples import sample_estimate
from bsp_ros.core.simulation import paper_mechanical_arm_cell, simulate_cell

BOOT_START_NS = 1000 * 10**9  # a controller clock counting from boot: 1000 s
WALL_START_NS = 1_717_225_200 * 10**9  # 2024-06-01T07:00:00Z


def _boot_stamped_bag(tmp_path: Path, *, receive_wall_clock: bool) -> Path:
    simulated = simulate_cell(paper_mechanical_arm_cell(duration_s=60.0, start_ns=BOOT_START_NS, seed=5))
    # A recorder on the wall clock receives the boot-stamped messages: receive time = stamp + (wall - boot).
    delay = WALL_START_NS - BOOT_START_NS if receive_wall_clock else 1_000_000
    bag = write_session_bag(tmp_path / "rec_boot", simulated.session, transport_delay_ns=delay)
    if receive_wall_clock:
        # Our writer logs /tf_static at its stamp; a wall-clock recorder would have received it then too.
        metadata = bag / "metadata.yaml"
        info = yaml.safe_load(metadata.read_text())
        info["rosbag2_bagfile_information"]["starting_time"]["nanoseconds_since_epoch"] = WALL_START_NS
        metadata.write_text(yaml.safe_dump(info))
    return bag


def _stored(store: Path, subject: str = "S1") -> list[Any]:
    with open_store(store) as opened:
        return opened.sessions(subject)


@pytest.mark.slow
def test_boot_stamped_bag_takes_the_wall_clock_recorded_start(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = _boot_stamped_bag(tmp_path, receive_wall_clock=True)
    store = tmp_path / "s.sqlite"
    code, out, err = bsp(capsys, "sessions", "add", str(bag), "--subject", "S1", "--store", str(store))
    assert code == 0, err
    assert "recorded start 2024-06-01T07:00:00Z" in out
    (record,) = _stored(store)
    assert record.session_time_ns == WALL_START_NS


@pytest.mark.slow
def test_boot_stamped_bag_without_a_wall_clock_asks_for_time(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = _boot_stamped_bag(tmp_path, receive_wall_clock=False)
    store = tmp_path / "s.sqlite"
    code, _, err = bsp(capsys, "sessions", "add", str(bag), "--subject", "S1", "--store", str(store))
    assert code != 0 and "--time" in err and "stamped from 1000" in err and "seconds or ms" not in err
    assert not store.exists() or not _stored_any(store)
    code, _, err = bsp(
        capsys, "sessions", "add", str(bag), "--subject", "S1", "--store", str(store), "--time", "2024-06-01"
    )
    assert code == 0, err
    (record,) = _stored(store)
    assert record.session_time_ns == WALL_START_NS - 7 * 3600 * 10**9


def _stored_any(store: Path) -> bool:
    with open_store(store) as opened:
        return bool(opened.subjects())


def test_boot_stamped_result_json_names_time_option(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    result = tmp_path / "r.json"
    result.write_text(json.dumps(sample_estimate(1, start_time_ns=BOOT_START_NS)))
    code, _, err = bsp(capsys, "sessions", "add", str(result), "--subject", "S1", "--store", str(tmp_path / "s.sq"))
    assert code != 0 and "--time" in err and "not a wall clock" in err


@pytest.mark.parametrize(
    "typed", ["2024-06-01T07:00:00Z", "2024-06-01 09:00:00+02:00", "2024-06-01T07:00", "1717225200", "1717225200.0"]
)
def test_time_accepts_what_users_type(tmp_path: Path, capsys: pytest.CaptureFixture[str], typed: str) -> None:
    result = tmp_path / "r.json"
    result.write_text(json.dumps(sample_estimate(1, start_time_ns=None)))
    store = tmp_path / "s.sqlite"
    code, _, err = bsp(
        capsys, "sessions", "add", str(result), "--subject", "S1", "--store", str(store), "--time", typed
    )
    assert code == 0, err
    assert _stored(store)[0].session_time_ns == WALL_START_NS


def test_time_accepts_a_date(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    result = tmp_path / "r.json"
    result.write_text(json.dumps(sample_estimate(1, start_time_ns=None)))
    store = tmp_path / "s.sqlite"
    assert (
        bsp(capsys, "sessions", "add", str(result), "--subject", "S1", "--store", str(store), "--time", "2024-06-01")[0]
        == 0
    )
    assert _stored(store)[0].session_time_ns == 1_717_200_000 * 10**9


@pytest.mark.parametrize("subject", ["Maria_Garcia_1984-03-12", "MariaGarcia", "P_19840312"])
def test_identifying_subject_ids_are_refused_with_the_reason(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], subject: str
) -> None:
    result = tmp_path / "r.json"
    result.write_text(json.dumps(sample_estimate(1)))
    store = tmp_path / "s.sqlite"
    code, _, err = bsp(capsys, "sessions", "add", str(result), "--subject", subject, "--store", str(store))
    assert code != 0 and "--allow-identifying-id" in err and ("date" in err or "name" in err)
    code, _, err = bsp(
        capsys, "sessions", "add", str(result), "--subject", subject, "--store", str(store), "--allow-identifying-id"
    )
    assert code == 0, err
    assert len(_stored(store, subject)) == 1


def test_pseudonyms_pass(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    result = tmp_path / "r.json"
    result.write_text(json.dumps(sample_estimate(1)))
    code, _, err = bsp(capsys, "sessions", "add", str(result), "--subject", "P007", "--store", str(tmp_path / "s.sq"))
    assert code == 0, err


def test_nan_inside_a_valid_estimate_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    estimate = sample_estimate(1, overrides={("joints", "elbow", "coulomb_nm"): (math.nan, 0.01)})
    result = tmp_path / "r.json"
    result.write_text(json.dumps(estimate))  # Python writes the NaN literal, as a careless exporter would
    store = tmp_path / "s.sqlite"
    code, _, err = bsp(capsys, "sessions", "add", str(result), "--subject", "S1", "--store", str(store))
    assert code != 0 and "joints.elbow.coulomb_nm.value is nan" in err and "marked valid" in err
    assert not _stored_any(store)


def test_invalid_estimate_is_stored_as_not_valid(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    estimate = sample_estimate(1, valid=False, overrides={("joints", "elbow", "coulomb_nm"): (math.nan, None)})
    result = tmp_path / "r.json"
    result.write_text(json.dumps(estimate))
    store = tmp_path / "s.sqlite"
    code, out, err = bsp(capsys, "sessions", "add", str(result), "--subject", "S1", "--store", str(store))
    assert code == 0 and "NOT VALID" in out, err
    (record,) = _stored(store)
    assert record.quality.valid is False
    assert record.parameters[("joints", "elbow", "coulomb_nm")].value is None


def _posture_bags(tmp_path: Path) -> list[Path]:
    """One session recorded upright and with the trunk tilted 25 deg, ten minutes apart (the same arm)."""
    import dataclasses

    from bsp_ros.core.simulation import human_arm_cell

    bags = []
    for k, (name, tilt_deg) in enumerate((("upright", 0.0), ("tilted", 25.0))):
        spec = human_arm_cell(duration_s=40.0, seed=7 + k, start_ns=WALL_START_NS + k * 600 * 10**9)
        centre = (spec.trajectory.center_deg[0] + tilt_deg, *spec.trajectory.center_deg[1:])
        trajectory = dataclasses.replace(spec.trajectory, center_deg=centre)
        spec = dataclasses.replace(spec, trunk_tilt_rad=math.radians(tilt_deg), trajectory=trajectory)
        bags.append(write_session_bag(tmp_path / name, simulate_cell(spec).session))
    return bags


@pytest.mark.slow
def test_the_recordings_of_two_postures_are_stored_as_one_session(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bags = [str(b) for b in _posture_bags(tmp_path)]
    store = tmp_path / "s.sqlite"
    common = ["--subject", "S1", "--store", str(store)]
    code, _, err = bsp(capsys, "sessions", "add", *bags, "--trunk-tilt-deg", "0", *common)
    assert code == 2 and "--trunk-tilt-deg gives 1 tilts (0) for 2 recordings" in err
    code, out, err = bsp(capsys, "sessions", "add", *bags, "--trunk-tilt-deg", "0", "25", *common)
    assert code == 0, err
    assert "added session 1 of S1" in out and "from upright + tilted" in out
    (record,) = _stored(store)
    assert record.config["trunk_tilt_deg"] == [0.0, 25.0] and record.source == "upright + tilted"
    assert record.repeatability  # the upright recording's cycles
    # The same two recordings again: refused before identifying, and nothing stored twice.
    code, _, err = bsp(capsys, "sessions", "add", *bags, "--trunk-tilt-deg", "0", "25", *common)
    assert code != 0 and "already" in err
    assert len(_stored(store)) == 1
    # A result JSON is one session already: it takes no second input and no tilts.
    result = tmp_path / "r.json"
    result.write_text(json.dumps(sample_estimate(3)))
    code, _, err = bsp(capsys, "sessions", "add", str(result), bags[0], *common)
    assert code == 2 and "give bags only" in err
