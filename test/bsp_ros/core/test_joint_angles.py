"""Joint angles, lengths and direction velocities from simulated markers with known truth."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.joint_angles import kinematics_from_markers, resample_kinematics, valid_stamps
from bsp_ros.core.streams import MarkerSeries
from bsp_ros.errors import DataError


def test_noise_free_angles_match_the_trajectory(human_session_noise_free, without_noise) -> None:
    session = human_session_noise_free
    kinematics = kinematics_from_markers(session.session.markers, 3)
    simulator = sim.CellSimulator(without_noise(sim.human_arm_cell(seed=1)))
    valid = np.isfinite(kinematics.q_rad).all(axis=1)
    truth = simulator.joint_angles_rad(simulator.seconds_since_start(kinematics.t_ns[valid]))
    np.testing.assert_allclose(kinematics.q_rad[valid], truth, atol=1e-6)


def test_lengths_are_within_a_millimetre_with_paper_noise(human_session) -> None:
    kinematics = kinematics_from_markers(human_session.session.markers, 3)
    np.testing.assert_allclose(kinematics.lengths_m, human_session.truth.lengths_m, atol=1e-3)
    assert (np.abs(kinematics.lengths_m - human_session.truth.lengths_m) < 3 * kinematics.lengths_std_m + 1e-9).all()


def test_direction_velocity_has_the_right_sign_at_003_rad_per_s(human_session) -> None:
    kinematics = kinematics_from_markers(human_session.session.markers, 3)
    simulator = sim.CellSimulator(sim.human_arm_cell(seed=7))
    valid = np.isfinite(kinematics.direction_velocity_rad_s).all(axis=1)
    truth = simulator.joint_velocities_rad_s(simulator.seconds_since_start(kinematics.t_ns[valid]))
    estimate = kinematics.direction_velocity_rad_s[valid]
    clear = np.abs(truth) > 0.1 * np.abs(truth).max(axis=0)  # away from the turning points
    agreement = (np.sign(estimate) == np.sign(truth))[clear].mean()
    assert agreement > 0.999
    noise = kinematics.direction_velocity_noise_rad_s
    assert (np.std(estimate - truth, axis=0) < 3 * noise).all()


def test_short_gaps_are_bridged_and_long_gaps_remove_frames(human_session_noise_free) -> None:
    markers = dict(human_session_noise_free.session.markers)
    elbow = markers["elbow"]
    t = elbow.t_ns
    short = (t > t[1000]) & (t < t[1004])  # 3 frames: 80 ms bridge
    long = (t > t[3000]) & (t < t[3100])  # 99 frames: 2 s
    keep = ~(short | long)
    markers["elbow"] = MarkerSeries(t[keep], elbow.position_m[keep])
    kinematics = kinematics_from_markers(markers, 3)
    assert kinematics.n_frames_bridged["elbow"] == 3
    invalid = ~np.isfinite(kinematics.q_rad).all(axis=1)
    gap = (kinematics.t_ns > t[3000]) & (kinematics.t_ns < t[3100])
    assert invalid[gap].all()
    assert kinematics.n_frames_invalid >= 99
    assert any("give no angle" in w for w in kinematics.warnings)


def test_resampling_onto_wrench_stamps_interpolates_and_marks_gaps(human_session_noise_free, without_noise) -> None:
    session = human_session_noise_free
    kinematics = kinematics_from_markers(session.session.markers, 3)
    t_ns = session.session.wrench.t_ns
    q, _, valid = resample_kinematics(kinematics, t_ns)
    simulator = sim.CellSimulator(without_noise(sim.human_arm_cell(seed=1)))
    truth = simulator.joint_angles_rad(simulator.seconds_since_start(t_ns[valid]))
    np.testing.assert_allclose(q[valid], truth, atol=1e-6)
    assert not np.isfinite(q[~valid]).any()


def test_valid_stamps_is_the_validity_of_resampling_without_interpolating(human_session_noise_free) -> None:
    """The wrench-delay profile asks only which shifted stamps have angles; the answer must be resample_kinematics'
    own: at frames beside a gap (NaN), before the first and after the last frame, and exactly on the last."""
    kinematics = kinematics_from_markers(human_session_noise_free.session.markers, 3)
    q_rad = kinematics.q_rad.copy()
    q_rad[300:304] = np.nan
    velocity = kinematics.direction_velocity_rad_s.copy()
    velocity[900, 1] = np.nan
    gappy = dataclasses.replace(kinematics, q_rad=q_rad, direction_velocity_rad_s=velocity)
    grid = gappy.t_ns
    wrench_t_ns = human_session_noise_free.session.wrench.t_ns
    stamps = np.concatenate(
        (wrench_t_ns, [grid[0] - 1, grid[0], grid[-1], grid[-1] + 1], grid[299:306], grid[899:902] + 7_000_000)
    )
    for shift_ns in (0, 20_000_000, -100_000_000):
        expected = resample_kinematics(gappy, stamps + shift_ns)[2]
        np.testing.assert_array_equal(valid_stamps(gappy, stamps + shift_ns), expected)
    assert not expected.all() and expected.any()


def test_nan_marker_frames_are_removed_and_counted(human_session_noise_free) -> None:
    markers = dict(human_session_noise_free.session.markers)
    position = markers["wrist"].position_m.copy()
    position[500:505] = np.nan
    markers["wrist"] = dataclasses.replace(markers["wrist"], position_m=position)
    kinematics = kinematics_from_markers(markers, 3)
    assert any("5 frames with non-finite positions" in w for w in kinematics.warnings)
    assert np.isfinite(kinematics.q_rad[505]).all()


def test_a_missing_marker_is_a_clear_error(human_session_noise_free) -> None:
    markers = {k: v for k, v in human_session_noise_free.session.markers.items() if k != "elbow"}
    with pytest.raises(DataError, match="elbow"):
        kinematics_from_markers(markers, 3)


def test_one_spike_in_a_live_angle_stream_does_not_inflate_the_velocity_noise() -> None:
    """The live window's path (kinematics_from_angles): a MAD noise level one sample cannot blow up."""
    from bsp_ros.core.joint_angles import kinematics_from_angles

    rng = np.random.default_rng(5)
    t_ns = 1_000_000_000 + 20_000_000 * np.arange(1500, dtype=np.int64)
    seconds = (t_ns - t_ns[0]) / 1e9
    q = np.column_stack([0.1 * np.sin(2 * np.pi * seconds / p) for p in (22.0, 19.0)]) + rng.normal(0, 1e-3, (1500, 2))
    before = kinematics_from_angles(t_ns, q, [0.3, 0.3], angle_filter=True).direction_velocity_noise_rad_s
    q[700, 1] += 0.5
    after = kinematics_from_angles(t_ns, q, [0.3, 0.3], angle_filter=True).direction_velocity_noise_rad_s
    np.testing.assert_allclose(after, before, rtol=0.05)


def test_angles_filtered_from_a_later_start_on_the_same_grid_settle_to_the_whole_run_s() -> None:
    """``grid`` continues an earlier call's grid (a live window filters its newest seconds anew): the points
    coincide, and 5 s from both ends of the shorter run its angles and derivatives are the whole run's, to 1e-6
    of their range (measured 3.3e-7 at most, the acceleration's: the zero-phase passes decay from the shorter run's
    padded start and end)."""
    from bsp_ros.core.joint_angles import kinematics_from_angles

    rng = np.random.default_rng(6)
    step_ns = 10_000_000
    t_ns = 1_000_000_000 + step_ns * np.arange(4000, dtype=np.int64) + rng.integers(-200_000, 200_000, 4000)
    seconds = (t_ns - t_ns[0]) / 1e9
    q = np.column_stack([0.6 * np.sin(2 * np.pi * seconds / p) for p in (9.0, 7.0, 5.0)])
    q += rng.normal(0, 1e-3, q.shape)
    whole = kinematics_from_angles(t_ns, q, [0.3, 0.27, 0.09], angle_filter=True)
    origin, grid_step = int(whole.t_ns[0]), int(whole.t_ns[1] - whole.t_ns[0])
    tail = kinematics_from_angles(
        t_ns[2500:],
        q[2500:],
        [0.3, 0.27, 0.09],
        whole.config,
        angle_filter=True,
        adapt_to_motion=False,
        grid=(origin, grid_step),
    )
    assert ((tail.t_ns - origin) % grid_step == 0).all() and tail.t_ns[0] >= t_ns[2500]
    inner = (tail.t_ns >= tail.t_ns[0] + 5_000_000_000) & (tail.t_ns <= tail.t_ns[-1] - 5_000_000_000)
    at = np.searchsorted(whole.t_ns, tail.t_ns[inner])
    assert inner.sum() > 400
    for name in ("q_rad", "direction_velocity_rad_s", "velocity_rad_s", "acceleration_rad_s2"):
        reference = getattr(whole, name)[at]
        span = np.ptp(reference, axis=0)
        np.testing.assert_allclose(getattr(tail, name)[inner], reference, rtol=0, atol=1e-6 * span.max(), err_msg=name)


def test_a_grid_coarser_than_the_angles_span_is_a_data_error() -> None:
    """A ``grid`` whose points the stamps cover fewer than 16 of cannot be filtered: a DataError naming the count."""
    from bsp_ros.core.joint_angles import kinematics_from_angles
    from bsp_ros.errors import DataError

    t_ns = 1_000_000_000 + 10_000_000 * np.arange(100, dtype=np.int64)  # 1.00-1.99 s at 100 Hz: 10 points 0.1 s apart
    q = np.zeros((100, 3))
    with pytest.raises(DataError, match="10 joint-angle grid points"):
        kinematics_from_angles(t_ns, q, [0.3, 0.27, 0.09], grid=(0, 100_000_000))
