"""The simulated sensor: turning with the handle (its /tf recovers the world wrench), filter delay, clock offset."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.bag import read_session, write_session_bag
from bsp_ros.bag.tare_reader import read_tare_bag
from bsp_ros.core.simulation import (
    CellSimulator,
    CellSpec,
    PassiveTruth,
    SensorSpec,
    human_arm_cell,
    simulate_cell,
)
from bsp_ros.errors import InputError
from msg_adapters import TransformSample, quaternion_from_matrix


def _quiet(spec: CellSpec, **sensor: object) -> CellSpec:
    """No noise or jitter; the given sensor fields."""
    return dataclasses.replace(
        spec,
        sensor=dataclasses.replace(spec.sensor, force_noise_n=0.0, torque_noise_nm=0.0, stamp_jitter_s=0.0, **sensor),
    )


def _write(out: Path, simulated) -> Path:
    samples = [
        TransformSample(int(t), "world", simulated.session.wrench.frame_id, np.zeros(3), quaternion_from_matrix(r))
        for t, r in zip(simulated.tf_t_ns.tolist(), simulated.tf_rotations_world_from_sensor, strict=True)
    ]
    return write_session_bag(out, simulated.session, simulated.truth.to_dict(), tf_static=False, tf_samples=samples)


def test_turning_sensor_bag_orientation_applied_per_sample_recovers_the_world_wrench(tmp_path: Path) -> None:
    base = human_arm_cell(seed=2, duration_s=20.0, inertia=True)
    spec = _quiet(base, turns_with_handle=True, handle_mass_kg=0.4, handle_com_m=(0.0, 0.02, 0.06))
    simulated = simulate_cell(spec)
    sim = CellSimulator(spec)
    bag = _write(tmp_path / "turning", simulated)
    read = read_tare_bag(bag)  # the wrench with its orientation per sample, slerped from /tf
    assert read.orientation_source == "tf" and read.rotations_world_from_sensor is not None
    np.testing.assert_array_equal(read.t_ns, simulated.session.wrench.t_ns)
    rotations = read.rotations_world_from_sensor
    force_world = np.einsum("nij,nj->ni", rotations, read.force_n)
    torque_world = np.einsum("nij,nj->ni", rotations, read.torque_nm)
    t_s = sim.seconds_since_start(read.t_ns)
    world = sim.wrench_world(t_s)
    weight = np.array([0.0, 0.0, -9.81 * 0.4])
    np.testing.assert_allclose(force_world[:, 1:] - weight[1:], world[:, :2], atol=1e-9)
    np.testing.assert_allclose(force_world[:, 0], 0.0, atol=1e-9)
    # The handle's COM turns with the sensor: its weight's moment is (R c) x m g in world.
    handle_moment = np.cross(rotations @ np.array([0.0, 0.02, 0.06]), weight)
    np.testing.assert_allclose(
        torque_world - handle_moment, np.column_stack([world[:, 2], 0 * world[:, :2]]), atol=1e-9
    )
    # The sensor really turned with the handle's pitch, about world x, around its session mean.
    pitch = np.degrees(sim.handle_pitch_rad(t_s))
    assert np.ptp(pitch) > 5.0 and abs(pitch.mean()) < 1.0
    angle = np.degrees(np.arctan2(rotations[:, 2, 1], rotations[:, 1, 1]))
    mount = np.degrees(np.arctan2(sim.rotation_world_from_sensor[2, 1], sim.rotation_world_from_sensor[1, 1]))
    np.testing.assert_allclose((angle - mount - pitch + 180.0) % 360.0 - 180.0, 0.0, atol=1e-6)
    # Taken with one fixed rotation, the wrench would be wrong by newtons.
    fixed = read.force_n @ sim.rotation_world_from_sensor.T
    assert np.abs(fixed[:, 1:] - weight[1:] - world[:, :2]).max() > 1.0
    truth = json.loads((bag / "truth.json").read_text())["simulation"]
    assert truth["sensor_turns_with_handle"] is True
    assert truth["handle_pitch_reference_rad"] == pytest.approx(np.radians(sum(spec.trajectory.center_deg)))
    assert read_session(bag).report.rotation_source == "tf"  # the session reader still opens it


@pytest.mark.parametrize(
    ("sensor", "delay_s"),
    [
        ({"filter_delay_s": 0.15}, 0.15),
        ({"filter_delay_s": 0.1, "filter_kind": "moving_average"}, 0.1),
        ({"average_over_period": True, "wrench_hz": 10.0}, 0.05),
        ({"clock_offset_s": 0.2}, 0.2),
        ({"filter_delay_s": 0.05, "average_over_period": True, "clock_offset_s": -0.08, "wrench_hz": 20.0}, -0.005),
    ],
)
def test_filter_averaging_and_clock_offset_delay_the_wrench_by_the_recorded_amount(
    tmp_path: Path, sensor: dict, delay_s: float
) -> None:
    """The bag's wrench matches the undelayed physics best when shifted by the recorded delay.

    The passive moment is smooth (viscous, no Coulomb step) so that a filter only delays the signal.
    """
    base = human_arm_cell(
        seed=3,
        duration_s=16.0,
        inertia=True,
        passive=PassiveTruth(coulomb_nm=(0.0, 0.0, 0.0), viscous_nms=(0.5, 0.2, 0.05)),
    )
    spec = _quiet(dataclasses.replace(base, trajectory=base.trajectory.speed_scaled(3.0)), **sensor)
    simulated = simulate_cell(spec)
    write_session_bag(tmp_path / "b", simulated.session, simulated.truth.to_dict())
    truth = json.loads((tmp_path / "b" / "truth.json").read_text())["simulation"]
    assert truth["wrench_delay_s"] == pytest.approx(delay_s, abs=1e-12)
    read = read_session(tmp_path / "b")
    reference = CellSimulator(dataclasses.replace(spec, sensor=SensorSpec(wrench_hz=spec.sensor.wrench_hz)))
    t_s = reference.seconds_since_start(read.session.wrench.t_ns)
    inner = (t_s > 1.0) & (t_s < 15.0)
    measured = read.session.wrench.force_n[inner] @ read.session.rotation_world_from_sensor.T

    def misfit(shift_s: float) -> float:
        return float(np.sqrt(np.mean((measured[:, 1:] - reference.wrench_world(t_s[inner] - shift_s)[:, :2]) ** 2)))

    coarse = np.linspace(-0.25, 0.25, 51)  # 10 ms steps, then 0.5 ms around the best
    best = coarse[np.argmin([misfit(s) for s in coarse])]
    fine = best + np.linspace(-0.01, 0.01, 41)
    best = fine[np.argmin([misfit(s) for s in fine])]
    assert best == pytest.approx(delay_s, abs=1.5e-3)
    assert misfit(delay_s) < 0.1 * misfit(0.0) or abs(delay_s) < 0.01


def test_filter_kernels_keep_mass_and_have_the_group_delay_as_their_mean() -> None:
    for sensor in (
        SensorSpec(filter_delay_s=0.03),
        SensorSpec(filter_delay_s=0.03, filter_kind="moving_average"),
        SensorSpec(filter_delay_s=0.03, average_over_period=True, wrench_hz=50.0),
    ):
        lags, weights = sensor.filter_kernel()
        assert weights.sum() == pytest.approx(1.0, abs=1e-14) and (lags >= 0).all()
        assert float(weights @ lags) == pytest.approx(sensor.delay_s, rel=1e-12)
    lags, weights = SensorSpec().filter_kernel()
    assert lags.tolist() == [0.0] and weights.tolist() == [1.0]


def test_a_filtered_turning_stream_sampled_in_chunks_equals_the_whole_session() -> None:
    spec = human_arm_cell(seed=5, duration_s=6.0, inertia=True)
    spec = dataclasses.replace(
        spec, sensor=dataclasses.replace(spec.sensor, turns_with_handle=True, filter_delay_s=0.02, clock_offset_s=0.01)
    )
    whole = CellSimulator(spec)
    stamps = whole.wrench_stamps_ns()
    all_at_once = whole.sample_wrench(stamps)
    chunked = CellSimulator(spec)
    chunked.wrench_stamps_ns()  # the same stamps draw
    parts = [chunked.sample_wrench(chunk) for chunk in np.array_split(stamps, 7)]
    np.testing.assert_array_equal(np.concatenate([p.force_n for p in parts]), all_at_once.force_n)
    np.testing.assert_array_equal(np.concatenate([p.torque_nm for p in parts]), all_at_once.torque_nm)


@pytest.mark.parametrize(
    ("field", "value", "named"),
    [
        ("filter_delay_s", -0.1, "filter_delay_s"),
        ("filter_delay_s", float("nan"), "filter_delay_s"),
        ("filter_kind", "butterworth", "filter_kind"),
        ("clock_offset_s", 2.0, "clock_offset_s"),
        ("turns_with_handle", 1, "turns_with_handle"),
        ("average_over_period", "yes", "average_over_period"),
    ],
)
def test_bad_sensor_timing_is_refused_naming_the_value(field: str, value: object, named: str) -> None:
    with pytest.raises(InputError, match=named):
        SensorSpec(**{field: value})
