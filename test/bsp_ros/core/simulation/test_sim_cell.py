"""Tests of the simulated cell against physics computed independently here (moment balance, geometry)."""

from __future__ import annotations

import dataclasses
import itertools
import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from bsp_ros.core.anthropometry import DE_LEVA, REFERENCE_HEIGHT_M
from bsp_ros.core.simulation import (
    DEFAULT_START_NS,
    CellSimulator,
    CellSpec,
    MarkerSpec,
    PassiveTruth,
    SensorSpec,
    SubjectTruth,
    TrajectorySpec,
    human_arm_cell,
    paper_mechanical_arm_cell,
    rotation_from_rpy_deg,
    simulate_cell,
)
from bsp_ros.errors import InputError

G = 9.81


def _noise_free(spec: CellSpec, rate_hz: float = 50.0) -> CellSpec:
    """Same cell, no noise or jitter, wrench and markers on one common clock."""
    return dataclasses.replace(
        spec,
        sensor=dataclasses.replace(
            spec.sensor, wrench_hz=rate_hz, phase_s=0.0, stamp_jitter_s=0.0, force_noise_n=0.0, torque_noise_nm=0.0
        ),
        markers=dataclasses.replace(spec.markers, marker_hz=rate_hz, phase_s=0.0, noise_m=0.0),
        duration_s=30.0,
    )


def _rich_passive_human(**overrides: Any) -> CellSpec:
    return human_arm_cell(
        **overrides,
        passive=PassiveTruth(
            coulomb_nm=(0.5, 0.28, 0.06),
            viscous_nms=(0.8, 0.3, 0.1),
            stiffness_nm_per_rad=(0.2, 1.2, 0.05),
            neutral_rad=(-0.5, 1.87, 0.0),
            offset_nm=(0.1, -0.2, 0.03),
        ),
    )


CELLS = {
    "human": human_arm_cell,
    "mechanical": paper_mechanical_arm_cell,
    "human_rich_passive": _rich_passive_human,
}


def _yz(session_markers: dict, names: tuple[str, ...]) -> list[np.ndarray]:
    return [session_markers[name].position_m[:, 1:] for name in names]


def _angles_from_markers(points: list[np.ndarray]) -> np.ndarray:
    """Relative joint angles from consecutive marker positions (y, z): (N, n)."""
    absolute = np.stack([np.arctan2(b[:, 1] - a[:, 1], b[:, 0] - a[:, 0]) for a, b in itertools.pairwise(points)], 1)
    return np.diff(absolute, axis=1, prepend=0.0)


def _trajectory_velocity(traj: TrajectorySpec, t_s: np.ndarray) -> np.ndarray:
    out = []
    for a, p, ph in zip(traj.amplitude_deg, traj.period_s, traj.phase_rad, strict=True):
        w = 2 * math.pi / p
        out.append(math.radians(a) * w * np.cos(w * t_s + ph))
    return np.stack(out, axis=1)


@pytest.mark.parametrize("cell", list(CELLS))
def test_contact_wrench_balances_gravity_and_passive_moment_about_every_joint(cell: str) -> None:
    spec = _noise_free(CELLS[cell](inertia=False))  # the quasi-static balance (dynamics: test_sim_dynamics)
    sim = simulate_cell(spec)
    session, truth = sim.session, sim.truth
    names = ("shoulder", "elbow", "wrist", "hand") if truth.n_segments == 3 else ("shoulder", "elbow", "hand")
    assert np.array_equal(session.wrench.t_ns, session.markers["hand"].t_ns)
    rot = session.rotation_world_from_sensor
    force = session.wrench.force_n @ rot.T  # world
    moment_x = (session.wrench.torque_nm @ rot.T)[:, 0]
    points = _yz(session.markers, names)
    q = _angles_from_markers(points)
    phi = np.cumsum(q, axis=1)
    beta = truth.static_moments_kgm
    t_s = (session.wrench.t_ns - spec.start_ns) * 1e-9
    qdot = _trajectory_velocity(truth.trajectory, t_s)
    p = truth.passive
    for i in range(truth.n_segments):
        gravity = G * sum(beta[j] * np.cos(phi[:, j]) for j in range(i, truth.n_segments))
        passive = (
            p.coulomb_nm[i] * np.sign(qdot[:, i])
            + p.viscous_nms[i] * qdot[:, i]
            + p.stiffness_nm_per_rad[i] * (q[:, i] - p.neutral_rad[i])
            + p.offset_nm[i]
        )
        lever = points[-1] - points[i]
        # Moment about joint i (about +x) of the robot's wrench on the hand, which is minus the hand's.
        robot_moment = -(lever[:, 0] * force[:, 2] - lever[:, 1] * force[:, 1]) - moment_x
        np.testing.assert_allclose(robot_moment, gravity + passive, atol=1e-9)


@pytest.mark.parametrize("cell", list(CELLS))
def test_wrench_has_no_out_of_plane_components_and_bearing_carries_no_moment(cell: str) -> None:
    sim = CellSimulator(_noise_free(CELLS[cell]()))
    wrench = sim.sample_wrench(sim.wrench_stamps_ns())
    rot = sim.rotation_world_from_sensor
    force, torque = wrench.force_n @ rot.T, wrench.torque_nm @ rot.T
    np.testing.assert_allclose(force[:, 0], 0.0, atol=1e-12)
    np.testing.assert_allclose(torque[:, 1:], 0.0, atol=1e-12)
    if sim.n_segments == 2:
        np.testing.assert_allclose(torque[:, 0], 0.0, atol=1e-12)
    else:
        assert np.abs(torque[:, 0]).max() > 0.01


@pytest.mark.parametrize("cell", ["human", "mechanical"])
def test_noise_free_markers_lie_at_segment_lengths_in_the_shoulder_plane(cell: str) -> None:
    spec = _noise_free(CELLS[cell]())
    simulated = simulate_cell(spec)
    session, truth = simulated.session, simulated.truth
    names = ("shoulder", "elbow", "wrist", "hand") if truth.n_segments == 3 else ("shoulder", "elbow", "hand")
    positions = [session.markers[name].position_m for name in names]
    for j, length in enumerate(truth.lengths_m):
        np.testing.assert_allclose(np.linalg.norm(positions[j + 1] - positions[j], axis=1), length, atol=1e-12)
    for xyz in positions:
        np.testing.assert_allclose(xyz[:, 0], spec.markers.shoulder_m[0], atol=1e-15)
    np.testing.assert_allclose(positions[0], np.broadcast_to(spec.markers.shoulder_m, positions[0].shape))


@pytest.mark.parametrize("cell", ["human", "mechanical"])
def test_noise_free_marker_angles_follow_the_trajectory(cell: str) -> None:
    spec = _noise_free(CELLS[cell]())
    session = simulate_cell(spec).session
    names = ("shoulder", "elbow", "wrist", "hand") if spec.n_segments == 3 else ("shoulder", "elbow", "hand")
    q = _angles_from_markers(_yz(session.markers, names))
    t_s = (session.markers["hand"].t_ns - spec.start_ns) * 1e-9
    tr = spec.trajectory
    expected = np.stack(
        [
            np.radians(c + a * np.sin(2 * np.pi * t_s / p + ph))
            for c, a, p, ph in zip(tr.center_deg, tr.amplitude_deg, tr.period_s, tr.phase_rad, strict=True)
        ],
        axis=1,
    )
    np.testing.assert_allclose(q, expected, atol=1e-12)
    # The arm hangs forward and down (q1 < 0) and the contact point is anterior of the shoulder.
    assert (q[:, 0] < 0).all()
    assert (session.markers["hand"].position_m[:, 1] > spec.markers.shoulder_m[1]).all()


def test_rotation_is_fixed_axis_roll_pitch_yaw() -> None:
    rot = rotation_from_rpy_deg(180.0, 0.0, 30.0)
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    rx = np.diag([1.0, -1.0, -1.0])
    np.testing.assert_allclose(rot, rz @ rx, atol=1e-15)
    general = rotation_from_rpy_deg(10.0, -20.0, 30.0)
    np.testing.assert_allclose(general @ general.T, np.eye(3), atol=1e-14)
    assert np.linalg.det(general) == pytest.approx(1.0)
    # Pitch alone turns +x toward -z (right-handed about +y).
    np.testing.assert_allclose(rotation_from_rpy_deg(0, 90, 0) @ [1, 0, 0], [0, 0, -1], atol=1e-15)


@pytest.mark.parametrize("rpy", [(180.0, 0.0, 30.0), (0.0, 0.0, 0.0), (12.0, -40.0, 95.0)])
def test_sensor_frame_wrench_rotates_back_to_world(rpy: tuple[float, float, float]) -> None:
    spec = _noise_free(human_arm_cell())
    spec = dataclasses.replace(spec, sensor=dataclasses.replace(spec.sensor, roll_pitch_yaw_deg=rpy))
    sim = CellSimulator(spec)
    stamps = sim.wrench_stamps_ns()
    wrench = sim.sample_wrench(stamps)
    world = sim.wrench_world(sim.seconds_since_start(stamps))
    rot = rotation_from_rpy_deg(*rpy)
    np.testing.assert_allclose((wrench.force_n @ rot.T)[:, 1:], world[:, :2], atol=1e-12)
    np.testing.assert_allclose((wrench.torque_nm @ rot.T)[:, 0], world[:, 2], atol=1e-12)
    assert wrench.frame_id == "ft_sensor"
    np.testing.assert_array_equal(sim.rotation_world_from_sensor, rot)


def test_bias_is_added_in_the_sensor_frame() -> None:
    base = _noise_free(human_arm_cell())
    biased = dataclasses.replace(
        base, sensor=dataclasses.replace(base.sensor, force_bias_n=(1.0, -2.0, 3.0), torque_bias_nm=(0.1, 0.2, -0.3))
    )
    clean, shifted = simulate_cell(base).session.wrench, simulate_cell(biased).session.wrench
    np.testing.assert_allclose(shifted.force_n - clean.force_n, np.broadcast_to([1.0, -2.0, 3.0], (clean.t_ns.size, 3)))
    np.testing.assert_allclose(
        shifted.torque_nm - clean.torque_nm, np.broadcast_to([0.1, 0.2, -0.3], (clean.t_ns.size, 3))
    )


def test_wrench_and_marker_noise_have_the_configured_spread() -> None:
    spec = human_arm_cell(duration_s=60.0)
    sim = CellSimulator(spec)
    stamps = sim.wrench_stamps_ns()
    wrench = sim.sample_wrench(stamps)
    rot = sim.rotation_world_from_sensor
    clean = sim.wrench_world(sim.seconds_since_start(stamps))
    clean_force = np.zeros((stamps.size, 3))
    clean_force[:, 1:] = clean[:, :2]
    clean_torque = np.zeros((stamps.size, 3))
    clean_torque[:, 0] = clean[:, 2]
    force_noise = wrench.force_n - clean_force @ rot
    torque_noise = wrench.torque_nm - clean_torque @ rot
    np.testing.assert_allclose(force_noise.std(axis=0), 0.05, rtol=0.05)
    np.testing.assert_allclose(torque_noise.std(axis=0), 0.005, rtol=0.05)
    np.testing.assert_allclose(force_noise.mean(axis=0), 0.0, atol=0.003)
    frames = sim.marker_stamps_ns()
    markers = sim.sample_markers(frames)
    exact = sim.marker_positions_m(sim.seconds_since_start(frames))
    for name, series in markers.items():
        np.testing.assert_allclose((series.position_m - exact[name]).std(axis=0), 1e-4, rtol=0.05)


@pytest.mark.parametrize("rate_hz", [50.0, 100.0, 1000.0, 5000.0])
def test_wrench_stamps_have_the_rate_jitter_and_a_realistic_epoch(rate_hz: float) -> None:
    spec = human_arm_cell(duration_s=20.0)
    spec = dataclasses.replace(spec, sensor=dataclasses.replace(spec.sensor, wrench_hz=rate_hz))
    stamps = CellSimulator(spec).wrench_stamps_ns()
    assert stamps.dtype == np.int64
    assert (np.diff(stamps) > 0).all()
    assert stamps.size == math.ceil((20.0 - 0.0013) * rate_hz)  # nominal times in [phase, duration)
    period_ns = 1e9 / rate_hz
    # Offsets from the epoch in int64 first: float64 cannot resolve single ns at 1.7e18.
    jitter = (stamps - DEFAULT_START_NS) - (1_300_000 + np.arange(stamps.size) * period_ns)
    assert np.median(np.diff(stamps)) == pytest.approx(period_ns, rel=1e-3)
    expected_sd = min(1e5, 0.4 * period_ns)  # clipped to +-0.4 period at high rates
    assert 0.5 * expected_sd < jitter.std() <= 1.05e5
    assert np.abs(jitter).max() <= 0.4 * period_ns + 1


def test_marker_frames_run_on_their_own_clock() -> None:
    spec = human_arm_cell(duration_s=10.0)
    sim = CellSimulator(spec)
    frames, stamps = sim.marker_stamps_ns(), sim.wrench_stamps_ns()
    np.testing.assert_array_equal(np.diff(frames), 20_000_000)
    assert frames[0] - DEFAULT_START_NS == 7_100_000
    assert np.intersect1d(frames, stamps).size == 0
    markers = simulate_cell(spec).session.markers
    assert set(markers) == {"shoulder", "elbow", "wrist", "hand"}
    assert all(series.t_ns.size == 500 for series in markers.values())


def test_two_segment_session_has_no_wrist_marker() -> None:
    session = simulate_cell(paper_mechanical_arm_cell(duration_s=5.0)).session
    assert set(session.markers) == {"shoulder", "elbow", "hand"}
    assert session.n_segments == 2


def test_dropouts_lose_the_configured_fraction_in_gaps_of_the_configured_length() -> None:
    spec = human_arm_cell(markers=MarkerSpec(dropout_fraction=0.2, dropout_mean_frames=5.0), duration_s=240.0)
    sim = CellSimulator(spec)
    frames = sim.marker_stamps_ns()
    markers = sim.sample_markers(frames)
    for series in markers.values():
        kept = np.isin(frames, series.t_ns)
        assert 1.0 - kept.mean() == pytest.approx(0.2, abs=0.03)
        lost_runs = np.diff(np.flatnonzero(np.diff(np.concatenate([[1], kept.astype(int), [1]])) != 0))[::2]
        assert lost_runs.mean() == pytest.approx(5.0, rel=0.2)
        assert series.position_m.shape == (series.t_ns.size, 3)
    visible = [np.isin(frames, s.t_ns) for s in markers.values()]
    assert not all(np.array_equal(visible[0], v) for v in visible[1:])  # markers drop out independently


def test_no_dropouts_by_default() -> None:
    sim = simulate_cell(human_arm_cell(duration_s=10.0))
    assert all(series.t_ns.size == 500 for series in sim.session.markers.values())


def test_mechanical_arm_truth_matches_paper_table_1() -> None:
    truth = simulate_cell(paper_mechanical_arm_cell(duration_s=1.0)).truth
    d = truth.to_dict()
    assert d["segments"]["forearm"]["first_moment_kgm"] == pytest.approx(0.130)
    assert d["segments"]["forearm"]["mass_kg"] == pytest.approx(1.160)
    assert d["segments"]["forearm"]["com_m"] == pytest.approx(0.130 / 1.160)
    assert d["segments"]["upper_arm"]["first_moment_kgm"] == pytest.approx(0.260)
    assert d["joints"]["elbow"]["coulomb_nm"] == pytest.approx(0.161)
    assert d["joints"]["shoulder"]["coulomb_nm"] == pytest.approx(0.139)
    # Grouped static moments (docs/contract.md) with the assumed a1 = 0.30 m: 0.260 + 0.30 * 1.160.
    assert d["segments"]["forearm"]["static_moment_kgm"] == pytest.approx(0.130)
    assert d["segments"]["upper_arm"]["static_moment_kgm"] == pytest.approx(0.608)
    assert set(d["segments"]) == {"upper_arm", "forearm"}
    tr = truth.trajectory
    assert tr.center_deg == (-36.6, 35.8) and tr.amplitude_deg == (5.7, 5.7)


def test_human_arm_defaults_come_from_the_anthropometric_table() -> None:
    subject = human_arm_cell().subject
    table = DE_LEVA["male"]
    scale = 1.78 / REFERENCE_HEIGHT_M["male"]
    for j, name in enumerate(("upper_arm", "forearm", "hand")):
        assert subject.lengths_m[j] == pytest.approx(table[name].length_m * scale)
        assert subject.masses_kg[j] == pytest.approx(table[name].mass_fraction * 75.0)
        assert subject.com_m[j] == pytest.approx(table[name].com_fraction * subject.lengths_m[j])
    m1, m2, m3 = subject.masses_kg
    l1, l2, l3 = subject.com_m
    a1, a2, _ = subject.lengths_m
    np.testing.assert_allclose(subject.static_moments_kgm, [m1 * l1 + a1 * (m2 + m3), m2 * l2 + a2 * m3, m3 * l3])


def test_prior_draw_is_reproducible_plausible_and_not_the_mean() -> None:
    draws = [SubjectTruth.from_anthropometry(rng=np.random.default_rng(7)) for _ in range(2)]
    assert draws[0] == draws[1]
    mean = SubjectTruth.from_anthropometry()
    assert draws[0].masses_kg != mean.masses_kg
    assert draws[0].lengths_m == mean.lengths_m
    many = [SubjectTruth.from_anthropometry(rng=np.random.default_rng(s)) for s in range(200)]
    forearm = np.array([s.masses_kg[1] for s in many])
    assert forearm.mean() == pytest.approx(0.0162 * 75.0, rel=0.05)
    assert forearm.std() == pytest.approx(0.0162 * 75.0 * 0.2, rel=0.25)


def test_default_trajectories_are_slow_and_velocities_are_the_derivative() -> None:
    for spec in (human_arm_cell(), paper_mechanical_arm_cell()):
        speeds = spec.trajectory.peak_speed_rad_s
        assert max(speeds) == pytest.approx(0.03, rel=0.05)
        sim = CellSimulator(spec)
        t = np.linspace(0.0, 60.0, 301)
        h = 1e-4
        numeric = (sim.joint_angles_rad(t + h) - sim.joint_angles_rad(t - h)) / (2 * h)
        np.testing.assert_allclose(sim.joint_velocities_rad_s(t), numeric, atol=1e-9)
        assert np.abs(sim.joint_velocities_rad_s(t)).max(axis=0) == pytest.approx(speeds, rel=1e-3)


def test_coulomb_moment_vanishes_at_exactly_zero_velocity() -> None:
    spec = human_arm_cell()
    still = dataclasses.replace(spec.trajectory, amplitude_deg=(6.0, 0.0, 0.9))
    sim = CellSimulator(dataclasses.replace(spec, trajectory=still))
    t = np.linspace(0.0, 30.0, 7)
    assert (sim.joint_velocities_rad_s(t)[:, 1] == 0.0).all()
    np.testing.assert_array_equal(sim.passive_torque_nm(t)[:, 1], 0.0)
    assert (np.abs(sim.passive_torque_nm(t)[:, 0]) == 0.5).all()


def _spec_with(**changes: Any) -> CellSpec:
    return human_arm_cell(**changes)


@pytest.mark.parametrize(
    ("build", "named"),
    [
        (lambda: SensorSpec(wrench_hz=0.5), "0.5"),
        (lambda: SensorSpec(wrench_hz=6000.0), "6000"),
        (lambda: SensorSpec(wrench_hz=float("nan")), "nan"),
        (lambda: MarkerSpec(marker_hz=0.0), "marker_hz"),
        (lambda: MarkerSpec(marker_hz=-50.0), "-50"),
        (lambda: MarkerSpec(dropout_fraction=0.95), "0.95"),
        (lambda: _spec_with(duration_s=0.0), "duration_s"),
        (lambda: _spec_with(duration_s=-3.0), "-3"),
        (lambda: _spec_with(seed=-1), "-1"),
        (lambda: _spec_with(start_ns=0), "start_ns"),
        (lambda: SubjectTruth((0.3, 0.3, 0.08), (2.0, -1.2, 0.4), (0.15, 0.12, 0.06)), "-1.2"),
        (lambda: SubjectTruth((0.3, 3.0, 0.08), (2.0, 1.2, 0.4), (0.15, 0.12, 0.06)), "3.0"),
        (lambda: SubjectTruth((0.3, 0.3, 0.08), (2.0, 1.2, 0.4), (0.15, 0.12)), "com_m"),
        (lambda: SubjectTruth((0.3,), (2.0,), (0.15,)), "got 1"),
        (lambda: SubjectTruth((0.3, 0.3, 0.1, 0.1), (2.0, 1.0, 0.4, 0.1), (0.1, 0.1, 0.05, 0.05)), "got 4"),
        (lambda: SubjectTruth((0.3, 0.3), (1.5, 1.2), (0.15, 0.9)), "0.9"),
        (lambda: PassiveTruth(coulomb_nm=(0.5, -0.28, 0.06)), "-0.28"),
        (lambda: PassiveTruth(coulomb_nm=(0.5, 0.28, 0.06), viscous_nms=(0.1, 0.2)), "viscous_nms"),
        (lambda: _spec_with(passive=PassiveTruth(coulomb_nm=(0.1, 0.1))), "passive has 2"),
        (lambda: TrajectorySpec((-40.0, 30.0), (5.0, 5.0), (20.0, 0.0), (0.0, 0.0)), "period_s[1]"),
        (
            lambda: _spec_with(trajectory=TrajectorySpec((-40.0, 3.0, 0.0), (5.0, 5.0, 1.0), (20.0,) * 3, (0.0,) * 3)),
            "elbow range 3.0",
        ),
        (lambda: _spec_with(colour="red"), "colour"),
    ],
)
def test_bad_specs_raise_input_error_naming_the_value(build: Callable[[], object], named: str) -> None:
    with pytest.raises(InputError) as info:
        build()
    assert named in str(info.value)


def test_sample_wrench_rejects_bad_stamps() -> None:
    sim = CellSimulator(human_arm_cell())
    with pytest.raises(InputError, match="not strictly increasing"):
        sim.sample_wrench(np.array([DEFAULT_START_NS + 10, DEFAULT_START_NS + 10], dtype=np.int64))
    with pytest.raises(InputError, match="0 or less"):
        sim.sample_markers(np.array([0, 1], dtype=np.int64))


def test_same_seed_gives_the_same_session_and_another_seed_does_not() -> None:
    a = simulate_cell(human_arm_cell(duration_s=20.0, markers=MarkerSpec(dropout_fraction=0.1), seed=3)).session
    b = simulate_cell(human_arm_cell(duration_s=20.0, markers=MarkerSpec(dropout_fraction=0.1), seed=3)).session
    c = simulate_cell(human_arm_cell(duration_s=20.0, markers=MarkerSpec(dropout_fraction=0.1), seed=4)).session
    np.testing.assert_array_equal(a.wrench.t_ns, b.wrench.t_ns)
    np.testing.assert_array_equal(a.wrench.force_n, b.wrench.force_n)
    for name in a.markers:
        np.testing.assert_array_equal(a.markers[name].t_ns, b.markers[name].t_ns)
        np.testing.assert_array_equal(a.markers[name].position_m, b.markers[name].position_m)
    assert not np.array_equal(a.wrench.force_n, c.wrench.force_n)
    assert not np.array_equal(a.markers["hand"].t_ns, c.markers["hand"].t_ns)


def test_streaming_in_chunks_equals_sampling_all_at_once() -> None:
    spec = human_arm_cell(duration_s=20.0, markers=MarkerSpec(dropout_fraction=0.2, dropout_mean_frames=4.0))
    batch = CellSimulator(spec)
    stream = CellSimulator(spec)
    stamps, frames = batch.wrench_stamps_ns(), batch.marker_stamps_ns()
    whole_w, whole_m = batch.sample_wrench(stamps), batch.sample_markers(frames)
    parts_w = [stream.sample_wrench(chunk) for chunk in np.array_split(stamps, 37)]
    parts_m = [stream.sample_markers(chunk) for chunk in np.array_split(frames, 23)]
    np.testing.assert_array_equal(np.concatenate([p.force_n for p in parts_w]), whole_w.force_n)
    np.testing.assert_array_equal(np.concatenate([p.torque_nm for p in parts_w]), whole_w.torque_nm)
    for name, series in whole_m.items():
        np.testing.assert_array_equal(np.concatenate([p[name].t_ns for p in parts_m]), series.t_ns)
        np.testing.assert_array_equal(np.concatenate([p[name].position_m for p in parts_m]), series.position_m)


# ---- nuisances (issue 10) -------------------------------------------------------------------------------


def _wrench_difference(nuisance: dict[str, Any], rpy: tuple[float, float, float] = (180.0, 0.0, 0.0)) -> tuple:
    """Sensor-frame wrench with the sensor nuisance minus the ideal cell's, at the same stamps (no noise)."""
    base = _noise_free(human_arm_cell())
    ideal = dataclasses.replace(base, sensor=dataclasses.replace(base.sensor, roll_pitch_yaw_deg=rpy))
    spoiled = dataclasses.replace(ideal, sensor=dataclasses.replace(ideal.sensor, **nuisance))
    a, b = CellSimulator(ideal), CellSimulator(spoiled)
    stamps = a.wrench_stamps_ns()
    wa, wb = a.sample_wrench(stamps), b.sample_wrench(stamps)
    return (stamps - base.start_ns) * 1e-9, wb.force_n - wa.force_n, wb.torque_nm - wa.torque_nm


def test_offset_drifts_linearly_from_its_value_at_the_session_start() -> None:
    t_s, d_force, d_torque = _wrench_difference(
        {
            "force_bias_n": (1.0, -2.0, 3.0),
            "force_drift_n_per_s": (0.01, 0.0, -0.02),
            "torque_bias_nm": (0.1, 0.0, -0.1),
            "torque_drift_nm_per_s": (0.0, 0.001, 0.0),
        }
    )
    np.testing.assert_allclose(d_force[:, 0], 1.0 + 0.01 * t_s, atol=1e-9)
    np.testing.assert_allclose(d_force[:, 1], -2.0, atol=1e-9)
    np.testing.assert_allclose(d_force[:, 2], 3.0 - 0.02 * t_s, atol=1e-9)
    np.testing.assert_allclose(d_torque, np.stack([0.1 + 0 * t_s, 0.001 * t_s, -0.1 + 0 * t_s], 1), atol=1e-9)


def test_handle_weight_loads_the_sensor_in_its_own_axes() -> None:
    # Sensor upside down (roll 180 deg): world -z is sensor +z, so the 0.3 kg handle pulls +2.943 N along
    # sensor z; its COM 0.1 m along sensor x gives c x F = (0, -0.1 * 2.943, 0) Nm.
    _, d_force, d_torque = _wrench_difference({"handle_mass_kg": 0.3, "handle_com_m": (0.1, 0.0, 0.0)})
    np.testing.assert_allclose(d_force, np.tile([0.0, 0.0, 0.3 * G], (d_force.shape[0], 1)), atol=1e-9)
    np.testing.assert_allclose(d_torque, np.tile([0.0, -0.1 * 0.3 * G, 0.0], (d_force.shape[0], 1)), atol=1e-9)


def test_handle_weight_rotates_with_the_sensor() -> None:
    # Pitch 90 deg: sensor x points to world -z, so the weight is +m g along sensor x; COM on sensor z.
    _, d_force, d_torque = _wrench_difference(
        {"handle_mass_kg": 0.5, "handle_com_m": (0.0, 0.0, 0.02)}, rpy=(0.0, 90.0, 0.0)
    )
    np.testing.assert_allclose(d_force[0], [0.5 * G, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(d_torque[0], [0.0, 0.02 * 0.5 * G, 0.0], atol=1e-9)


def test_smooth_friction_follows_tanh_of_the_transition_width() -> None:
    passive = PassiveTruth(coulomb_nm=(0.5, 0.28, 0.06), friction_transition_rad_s=0.002)
    v = np.array([[0.0, 0.002, -0.01], [0.001, -0.0005, 1.0]])
    expected = np.array(
        [[0.0, 0.28 * math.tanh(1.0), -0.06 * math.tanh(5.0)], [0.5 * math.tanh(0.5), -0.28 * math.tanh(0.25), 0.06]]
    )
    np.testing.assert_allclose(passive.friction_nm(v), expected, rtol=1e-12, atol=1e-15)


def test_stribeck_shape_sticks_more_at_low_speed_and_decays_to_coulomb() -> None:
    passive = PassiveTruth(coulomb_nm=(0.5, 0.2), stribeck_ratio=1.5, stribeck_speed_rad_s=0.01)
    v = np.array([[1e-9, -0.01], [0.1, -1.0]])
    expected = np.array(
        [[0.5 * 1.5, -0.2 * (1.0 + 0.5 * math.exp(-1.0))], [0.5 * (1.0 + 0.5 * math.exp(-100.0)), -0.2]]
    )
    np.testing.assert_allclose(passive.friction_nm(v), expected, rtol=1e-9)


def test_simulated_passive_moment_uses_the_friction_shape() -> None:
    spec = human_arm_cell(passive=PassiveTruth(coulomb_nm=(0.5, 0.28, 0.06), friction_transition_rad_s=0.005))
    sim = CellSimulator(spec)
    t_s = np.linspace(0.0, 30.0, 301)
    qdot = spec.trajectory.velocities_rad_s(t_s)
    np.testing.assert_allclose(sim.passive_torque_nm(t_s), np.array([0.5, 0.28, 0.06]) * np.tanh(qdot / 0.005))


def test_skin_markers_sit_at_their_offset_in_the_segment_frame() -> None:
    offsets = ((0.0, 0.01), (0.02, 0.0), (0.0, -0.01), (0.01, 0.01))
    base = _noise_free(human_arm_cell())
    spoiled = dataclasses.replace(base, markers=dataclasses.replace(base.markers, skin_offset_m=offsets))
    t_s = np.array([0.0, 7.3])
    clean, skin = CellSimulator(base).marker_positions_m(t_s), CellSimulator(spoiled).marker_positions_m(t_s)
    phi = np.cumsum(base.trajectory.angles_rad(t_s), axis=1)
    for i, name in enumerate(("shoulder", "elbow", "wrist", "hand")):
        angle = phi[:, min(i, 2)]
        along, normal = offsets[i]
        dy = along * np.cos(angle) - normal * np.sin(angle)
        dz = along * np.sin(angle) + normal * np.cos(angle)
        np.testing.assert_allclose(skin[name] - clean[name], np.stack([0 * dy, dy, dz], 1), atol=1e-12)


def test_skin_offsets_need_one_pair_per_marker() -> None:
    with pytest.raises(InputError, match="skin_offset_m"):
        paper_mechanical_arm_cell(markers=MarkerSpec(skin_offset_m=((0.0, 0.01),) * 4))


def test_lost_tf_static_leaves_the_session_without_its_rotation() -> None:
    spec = human_arm_cell(duration_s=5.0, sensor=SensorSpec(tf_static=False))
    simulated = simulate_cell(spec)
    np.testing.assert_array_equal(simulated.session.rotation_world_from_sensor, np.eye(3))
    assert simulated.truth.simulation["tf_static"] is False
    assert simulated.truth.simulation["sensor_roll_pitch_yaw_deg"] == [180.0, 0.0, 30.0]


def test_spikes_hit_the_configured_fraction_with_the_configured_size_and_nothing_else() -> None:
    base = human_arm_cell(duration_s=60.0)
    spiked = dataclasses.replace(base, sensor=SensorSpec(spike_fraction=0.01, spike_n=1000.0))
    a, b = simulate_cell(base).session, simulate_cell(spiked).session
    difference = b.wrench.force_n - a.wrench.force_n
    hit = np.abs(difference).max(axis=1) > 0
    assert 30 <= hit.sum() <= 90  # 6000 samples at 1 %: 60 +- 7.7
    np.testing.assert_allclose(np.abs(difference[hit]).sum(axis=1), 1000.0)  # one axis, +-1000 N
    assert (np.count_nonzero(difference[hit], axis=1) == 1).all()
    np.testing.assert_array_equal(b.wrench.torque_nm, a.wrench.torque_nm)
    np.testing.assert_array_equal(b.markers["hand"].position_m, a.markers["hand"].position_m)
