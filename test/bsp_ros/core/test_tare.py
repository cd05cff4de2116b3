"""Tare estimation and application against simulated tare recordings with known offset and handle."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.core.simulation import (
    SensorSpec,
    TareSpec,
    human_arm_cell,
    rotation_from_rpy_deg,
    simulate_cell,
    simulate_tare,
    tare_rotations,
)
from bsp_ros.core.tare import (
    Tare,
    corrected_session,
    estimate_tare,
    read_tare_file,
    recording_warnings,
    tare_warnings,
    tare_wrench,
    write_tare_file,
)
from bsp_ros.errors import DataError, InputError

G = 9.81
SENSOR = SensorSpec(
    force_bias_n=(3.0, -1.0, 2.0),
    torque_bias_nm=(0.1, 0.05, -0.02),
    handle_mass_kg=0.3,
    handle_com_m=(0.01, -0.02, 0.05),
)
SWING = TareSpec(duration_s=20.0, swing_rpy_deg=(20.0, 20.0, 0.0))


def _tare(seed: int = 0, sensor: SensorSpec = SENSOR, spec: TareSpec = SWING) -> tuple[Tare, np.ndarray]:
    cell = human_arm_cell(sensor=sensor, seed=seed)
    recording = simulate_tare(cell, spec)
    rotations = tare_rotations(cell, spec, (recording.wrench.t_ns - cell.start_ns) * 1e-9 - spec.start_offset_s)
    tare = estimate_tare(
        recording.wrench.t_ns, recording.wrench.force_n, recording.wrench.torque_nm, "ft_sensor", rotations
    )
    truth = np.array([3.0, -1.0, 2.0, 0.3, 0.1, 0.05, -0.02, *(0.3 * np.array(SENSOR.handle_com_m))])
    return tare, truth


def test_swinging_tare_separates_offset_mass_and_com() -> None:
    tare, truth = _tare()
    assert tare.load == "separated"
    assert min(tare.swing_deg) > 3.0
    # One seed, ten parameters: 4 std here; the std's calibration is tested over seeds below.
    assert np.all(np.abs(tare.values - truth) < 4.0 * tare.std)
    mass, com = tare.handle_mass_kg, tare.handle_com_m
    assert mass is not None and com is not None
    assert mass[0] == pytest.approx(0.3, abs=0.002)
    np.testing.assert_allclose(com[0], SENSOR.handle_com_m, atol=0.001)


def test_tare_std_matches_the_scatter_over_seeds() -> None:
    runs = [_tare(seed) for seed in range(30)]
    values = np.array([t.values for t, _ in runs])
    reported = np.array([t.std for t, _ in runs]).mean(axis=0)
    ratio = values.std(axis=0, ddof=1) / reported
    # 30 draws: the sample std of a calibrated estimate lies within about +-30% of the true one.
    assert np.all((ratio > 0.65) & (ratio < 1.4)), ratio


def test_tare_at_rest_gives_the_constant_load_at_that_orientation() -> None:
    tare, _ = _tare(spec=TareSpec(duration_s=20.0))
    assert tare.load == "constant" and tare.handle_mass_kg is None
    rotation = SENSOR.rotation_world_from_sensor
    weight = rotation.T @ np.array([0.0, 0.0, -0.3 * G])
    expected_force = np.array(SENSOR.force_bias_n) + weight
    expected_torque = np.array(SENSOR.torque_bias_nm) + np.cross(SENSOR.handle_com_m, weight)
    force, force_std = tare.force_offset_n
    torque, torque_std = tare.torque_offset_nm
    assert np.all(np.abs(force - expected_force) < 4 * force_std)
    assert np.all(np.abs(torque - expected_torque) < 4 * torque_std)


def test_unknown_orientation_gives_the_constant_load() -> None:
    recording = simulate_tare(human_arm_cell(sensor=SENSOR), SWING)
    w = recording.wrench
    tare = estimate_tare(w.t_ns, w.force_n, w.torque_nm, "ft_sensor", None)
    assert tare.load == "constant" and tare.rotation_world_from_sensor is None


def test_wrench_jacobian_predicts_what_the_simulator_adds_for_a_handle() -> None:
    tare, truth = _tare()
    exact = dataclasses.replace(tare, values=truth)
    for rpy in ((180.0, 0.0, 30.0), (12.0, -40.0, 95.0)):
        rotation = rotation_from_rpy_deg(*rpy)
        force, torque = exact.predicted_wrench(rotation)
        load_f, load_m = SENSOR.payload_wrench(rotation)
        np.testing.assert_allclose(force, np.array(SENSOR.force_bias_n) + load_f, atol=1e-12)
        np.testing.assert_allclose(torque, np.array(SENSOR.torque_bias_nm) + load_m, atol=1e-12)


def test_tare_wrench_removes_offset_and_handle_from_a_session() -> None:
    quiet = dataclasses.replace(SENSOR, force_noise_n=0.0, torque_noise_nm=0.0)
    spoiled = simulate_cell(human_arm_cell(sensor=quiet, duration_s=5.0)).session
    ideal = simulate_cell(
        human_arm_cell(sensor=SensorSpec(force_noise_n=0.0, torque_noise_nm=0.0), duration_s=5.0)
    ).session
    tare, truth = _tare()
    exact = dataclasses.replace(tare, values=truth)
    corrected = corrected_session(spoiled, exact)
    np.testing.assert_allclose(corrected.wrench.force_n, ideal.wrench.force_n, atol=1e-9)
    np.testing.assert_allclose(corrected.wrench.torque_nm, ideal.wrench.torque_nm, atol=1e-9)
    _, _, covariance, warnings = tare_wrench(spoiled.wrench, tare, spoiled.rotation_world_from_sensor)
    h = tare.wrench_jacobian(spoiled.rotation_world_from_sensor)
    np.testing.assert_allclose(covariance, h @ tare.covariance @ h.T)
    assert warnings == []


def test_tare_of_another_frame_is_refused() -> None:
    session = simulate_cell(human_arm_cell(duration_s=2.0)).session
    tare, _ = _tare()
    with pytest.raises(InputError, match="frame 'ft_other'"):
        tare_wrench(session.wrench, dataclasses.replace(tare, frame_id="ft_other"), np.eye(3))


def test_constant_load_applied_at_another_tilt_warns() -> None:
    tare, _ = _tare(spec=TareSpec(duration_s=20.0))
    assert tare_warnings(tare, SENSOR.rotation_world_from_sensor) == []
    tilted = SENSOR.rotation_world_from_sensor @ rotation_from_rpy_deg(0.0, 10.0, 0.0)
    (warning,) = tare_warnings(tare, tilted)
    assert "tilted up to 10 deg" in warning


@pytest.mark.parametrize(
    ("cut", "error", "match"),
    [
        (slice(0, 400), DataError, "lasts 3.99 s"),
        (slice(0, 30), DataError, "30 wrench samples"),
    ],
)
def test_short_recordings_are_refused(cut: slice, error: type, match: str) -> None:
    w = simulate_tare(human_arm_cell(sensor=SENSOR), SWING).wrench
    with pytest.raises(error, match=match):
        estimate_tare(w.t_ns[cut], w.force_n[cut], w.torque_nm[cut], "ft_sensor")


def test_nan_samples_are_refused_naming_the_first() -> None:
    w = simulate_tare(human_arm_cell(sensor=SENSOR), SWING).wrench
    force = w.force_n.copy()
    force[[17, 40], 1] = math.nan
    with pytest.raises(DataError, match=r"2 wrench samples with NaN/Inf \(the first at index 17"):
        estimate_tare(w.t_ns, force, w.torque_nm, "ft_sensor")


def test_mismatched_shapes_are_refused() -> None:
    w = simulate_tare(human_arm_cell(sensor=SENSOR), SWING).wrench
    with pytest.raises(InputError, match="tare wrench must be"):
        estimate_tare(w.t_ns, w.force_n[:-1], w.torque_nm, "ft_sensor")


def test_tare_file_round_trips_and_is_not_overwritten(tmp_path: Path) -> None:
    tare, _ = _tare()
    path = write_tare_file(tmp_path / "cell.tare.yaml", tare)
    back = read_tare_file(path)
    assert back.to_dict() == tare.to_dict() and back.file == "cell.tare.yaml"
    np.testing.assert_array_equal(back.covariance, tare.covariance)
    with pytest.raises(InputError, match="exists already"):
        write_tare_file(path, tare)


def test_foreign_or_broken_tare_files_are_refused(tmp_path: Path) -> None:
    (tmp_path / "a.yaml").write_text("schema: bsp_ros/core/estimate/1\n")
    with pytest.raises(InputError, match="tare schema"):
        read_tare_file(tmp_path / "a.yaml")
    tare, _ = _tare()
    data = tare.to_dict()
    del data["payload"]
    with pytest.raises(InputError, match="missing or malformed"):
        Tare.from_dict(data)
    with pytest.raises(InputError, match="does not exist"):
        read_tare_file(tmp_path / "none.yaml")


def test_a_tare_far_from_the_session_orientation_points_at_a_lost_transform() -> None:
    tare, _ = _tare()
    assert tare_warnings(tare, SENSOR.rotation_world_from_sensor) == []
    (warning,) = tare_warnings(tare, np.eye(3))  # what a session bag without /tf_static gives
    assert "lost or wrong world -> sensor transform" in warning and "180 deg" in warning


def test_spikes_are_left_out_and_counted() -> None:
    cell = human_arm_cell(sensor=SENSOR, seed=2)
    recording = simulate_tare(cell, SWING)
    rotations = tare_rotations(cell, SWING, (recording.wrench.t_ns - cell.start_ns) * 1e-9 - SWING.start_offset_s)
    w = recording.wrench
    clean = estimate_tare(w.t_ns, w.force_n, w.torque_nm, "ft_sensor", rotations)
    force, torque = w.force_n.copy(), w.torque_nm.copy()
    spikes = np.random.default_rng(5).choice(w.t_ns.size, 10, replace=False)
    force[spikes, 2] += 1000.0  # ten 1 kN knocks
    torque[spikes[:3], 0] -= 50.0
    spiked = estimate_tare(w.t_ns, force, torque, "ft_sensor", rotations)
    assert spiked.n_rejected == 10 and clean.n_rejected == 0
    assert np.all(np.abs(spiked.values - clean.values) < 0.2 * clean.std)


def test_a_handle_touched_during_the_tare_is_refused() -> None:
    w = simulate_tare(human_arm_cell(sensor=SENSOR), TareSpec(duration_s=20.0)).wrench
    force = w.force_n.copy()
    force[500:900, 1] += 5.0  # 4 s of a hand resting on the handle
    with pytest.raises(DataError, match="not steady: 400 of 2000"):
        estimate_tare(w.t_ns, force, w.torque_nm, "ft_sensor")


def test_a_load_that_changes_during_the_tare_is_called_unsteady() -> None:
    steady, _ = _tare()
    assert steady.unsteadiness < 1.3 and recording_warnings(steady) == []
    w = simulate_tare(human_arm_cell(sensor=SENSOR), TareSpec(duration_s=20.0)).wrench
    t_s = (w.t_ns - w.t_ns[0]) * 1e-9
    force = w.force_n + np.stack([0 * t_s, 2.0 * np.sin(2 * np.pi * t_s / 19.0), 0 * t_s], 1)  # an arm moving
    unsteady = estimate_tare(w.t_ns, force, w.torque_nm, "ft_sensor")
    (warning,) = recording_warnings(unsteady)
    assert unsteady.unsteadiness > 20 and "the load changed during the recording" in warning
    assert unsteady.force_offset_n[1][1] > 0.1  # and its std says how little it is worth


def test_a_tare_s_note_reaches_the_estimate_as_a_finding() -> None:
    """A tare taken in another orientation than the session's (here: a session without its sensor rotation)."""
    tare, _ = _tare()
    session = simulate_cell(human_arm_cell(sensor=SENSOR, seed=0, duration_s=40.0)).session
    unrotated = dataclasses.replace(session, rotation_world_from_sensor=np.eye(3))
    document = identify_session(unrotated, IdentifyOptions(tare=tare))
    notes = [f for f in findings_of(document["quality"]) if f.code is FindingCode.TARE_NOTE]
    assert any("lost or wrong world -> sensor transform" in f.text for f in notes), document["quality"]["warnings"]
    assert all(f.text in document["quality"]["warnings"] for f in notes)
