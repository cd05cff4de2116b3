"""Simulated tare recordings: the handle free, at rest or swinging, whole or streamed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bsp_ros.core.simulation import (
    DEFAULT_START_NS,
    CellSimulator,
    SensorSpec,
    TareSpec,
    human_arm_cell,
    rotation_from_rpy_deg,
    simulate_tare,
)

G = 9.81


def test_tare_at_rest_measures_offset_plus_the_handle_load() -> None:
    sensor = SensorSpec(
        roll_pitch_yaw_deg=(180.0, 0.0, 0.0),
        force_bias_n=(1.0, 2.0, 3.0),
        torque_bias_nm=(0.1, 0.0, 0.0),
        force_drift_n_per_s=(0.001, 0.0, 0.0),
        handle_mass_kg=0.3,
        handle_com_m=(0.1, 0.0, 0.0),
        force_noise_n=0.0,
        torque_noise_nm=0.0,
    )
    tare = simulate_tare(human_arm_cell(sensor=sensor), TareSpec(duration_s=10.0, start_offset_s=-100.0))
    t_s = (tare.wrench.t_ns - DEFAULT_START_NS) * 1e-9  # about -100 .. -90 s
    assert tare.tf_t_ns.size == 0
    np.testing.assert_allclose(tare.wrench.force_n[:, 0], 1.0 + 0.001 * t_s, atol=1e-9)
    np.testing.assert_allclose(tare.wrench.force_n[:, 1:], np.tile([2.0, 3.0 + 0.3 * G], (t_s.size, 1)), atol=1e-9)
    np.testing.assert_allclose(tare.wrench.torque_nm, np.tile([0.1, -0.1 * 0.3 * G, 0.0], (t_s.size, 1)), atol=1e-9)
    assert tare.truth["force_offset_n"] == pytest.approx([1.0 - 0.001 * 95.0, 2.0, 3.0])


def test_swinging_tare_publishes_the_orientation_the_wrench_follows() -> None:
    sensor = SensorSpec(handle_mass_kg=0.3, force_noise_n=0.0, torque_noise_nm=0.0, stamp_jitter_s=0.0)
    spec = human_arm_cell(sensor=sensor)
    tare = simulate_tare(spec, TareSpec(duration_s=10.0, swing_rpy_deg=(20.0, 30.0, 0.0), swing_period_s=5.0))
    assert tare.tf_t_ns.size == 500
    # At t = 0 of the tare the swing is (0, 30 sin(2 pi / 3), 0) deg about the mounting orientation.
    expected = spec.sensor.rotation_world_from_sensor @ rotation_from_rpy_deg(
        0.0, 30.0 * math.sin(2 * math.pi / 3), 0.0
    )
    np.testing.assert_allclose(tare.rotations_world_from_sensor[0], expected, atol=1e-12)
    # A tf sample that coincides with a wrench stamp: the force is R^T (0, 0, -m g).
    k = int(np.searchsorted(tare.wrench.t_ns, tare.tf_t_ns[100]))
    assert tare.wrench.t_ns[k] - tare.tf_t_ns[100] == pytest.approx(1_300_000, abs=1)  # the 1.3 ms wrench phase
    rotation = tare.rotations_world_from_sensor[100]
    force_world = rotation @ tare.wrench.force_n[k]
    np.testing.assert_allclose(force_world, [0.0, 0.0, -0.3 * G], atol=0.02)  # 1.3 ms of swing apart


def test_streamed_tare_wrench_matches_the_whole_recording_physics() -> None:
    sensor = SensorSpec(handle_mass_kg=0.3, handle_com_m=(0.0, 0.0, 0.05), force_noise_n=0.0, torque_noise_nm=0.0)
    spec = human_arm_cell(sensor=sensor)
    tare = TareSpec(duration_s=10.0, swing_rpy_deg=(10.0, 15.0, 0.0))
    whole = simulate_tare(spec, tare)
    streamed, rotations = CellSimulator(spec).sample_tare_wrench(whole.wrench.t_ns[:300], tare)
    np.testing.assert_allclose(streamed.force_n, whole.wrench.force_n[:300], atol=1e-12)
    np.testing.assert_allclose(streamed.torque_nm, whole.wrench.torque_nm[:300], atol=1e-12)
    weight = np.einsum("nji,j->ni", rotations, [0.0, 0.0, -0.3 * G])  # R^T (0, 0, -m g)
    np.testing.assert_allclose(streamed.force_n, weight, atol=1e-12)
