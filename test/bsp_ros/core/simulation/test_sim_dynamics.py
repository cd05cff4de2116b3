"""The simulator's rigid-body dynamics against pinocchio, energy conservation and the statics limit."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from pinocchio_chain import planar_chain

from bsp_ros.core.anthropometry import inertia_com_kgm2
from bsp_ros.core.simulation import (
    CellSimulator,
    CellSpec,
    PassiveTruth,
    PlanarChain,
    SessionTruth,
    SubjectTruth,
    human_arm_cell,
    inverse_dynamics_nm,
    paper_mechanical_arm_cell,
    simulate_cell,
)
from bsp_ros.errors import InputError

G = 9.81
GOLDEN = Path(__file__).parents[3] / "data" / "simulation_quasistatic_3f2534c.json"


def _subject(n: int) -> SubjectTruth:
    """An arm with COMs off the axes and unequal inertias (nothing cancels by symmetry)."""
    base = SubjectTruth.from_anthropometry(n_segments=n)
    return dataclasses.replace(base, com_perpendicular_m=(0.012, -0.02, 0.015)[:n])


def _chain(subject: SubjectTruth) -> PlanarChain:
    return PlanarChain(
        subject.lengths_m, subject.masses_kg, subject.com_m, subject.com_perpendicular_m, subject.inertia_com_kgm2
    )


def _pinocchio_model(subject: SubjectTruth):
    """The same chain as a pinocchio model."""
    pin = pytest.importorskip("pinocchio")  # the test extra installs it (PyPI: pin)
    return planar_chain(
        pin, subject.lengths_m, subject.masses_kg, subject.com_m, subject.com_perpendicular_m,
        subject.inertia_com_kgm2, gravity_m_s2=G,
    )  # fmt: skip


@pytest.mark.parametrize("n", [2, 3])
def test_newton_euler_torques_equal_pinocchio_rnea(n: int) -> None:
    subject = _subject(n)
    model = _pinocchio_model(subject)
    data = model.createData()
    pin = pytest.importorskip("pinocchio")
    rng = np.random.default_rng(7)
    q, qd, qdd = rng.uniform(-1.5, 1.5, (3, 40, n))
    expected = np.array([pin.rnea(model, data, q[k], qd[k], qdd[k]) for k in range(q.shape[0])])
    ours = inverse_dynamics_nm(_chain(subject), q, qd, qdd)
    np.testing.assert_allclose(ours, expected, rtol=0.0, atol=1e-10)
    assert np.abs(expected).max() > 1.0  # the comparison is not of small numbers


def test_static_limit_is_the_closed_form_gravity_torque() -> None:
    spec = human_arm_cell(subject=_subject(3), inertia=True)
    sim = CellSimulator(spec)
    t = np.linspace(0.0, 30.0, 61)
    q = sim.joint_angles_rad(t)
    zero = np.zeros_like(q)
    np.testing.assert_allclose(
        inverse_dynamics_nm(_chain(spec.subject), q, zero, zero), sim.gravity_torque_nm(t), rtol=0, atol=1e-12
    )


def test_energy_balance_power_in_equals_kinetic_plus_potential_change() -> None:
    """Over a fast motion, the work of the joint torques equals the change of kinetic + potential energy."""
    subject = _subject(3)
    chain = _chain(subject)
    spec = human_arm_cell(subject=subject, inertia=True)
    trajectory = spec.trajectory.speed_scaled(20.0)  # ~0.6 rad/s: inertia matters
    t = np.linspace(0.0, 1.5, 30001)
    q, qd, qdd = trajectory.angles_rad(t), trajectory.velocities_rad_s(t), trajectory.accelerations_rad_s2(t)
    tau = inverse_dynamics_nm(chain, q, qd, qdd)
    power = np.sum(tau * qd, axis=1)
    work = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(t))])
    # Kinetic energy 0.5 qd^T M qd with M's columns from the recursion without gravity and velocity.
    no_gravity = dataclasses.replace(chain, gravity_m_s2=0.0)
    zero = np.zeros_like(q)
    mass_columns = [inverse_dynamics_nm(no_gravity, q, zero, np.broadcast_to(e, q.shape)) for e in np.eye(3)]
    m_qd = sum(col * qd[:, [k]] for k, col in enumerate(mass_columns))
    kinetic = 0.5 * np.sum(qd * m_qd, axis=1)
    # Potential energy from the COM heights, computed here from the geometry.
    phi = np.cumsum(q, axis=1)
    joint_z = np.concatenate([np.zeros((t.size, 1)), np.cumsum(np.asarray(subject.lengths_m) * np.sin(phi), 1)], 1)
    com_z = (
        joint_z[:, :-1]
        + np.asarray(subject.com_m) * np.sin(phi)
        + np.asarray(subject.com_perpendicular_m) * np.cos(phi)
    )
    potential = G * np.sum(np.asarray(subject.masses_kg) * com_z, axis=1)
    energy = kinetic + potential
    np.testing.assert_allclose(work, energy - energy[0], rtol=0, atol=1e-6)
    assert np.ptp(kinetic) > 1e-3  # the motion is fast enough to test the inertial terms


def test_inertial_wrench_grows_with_the_square_of_the_speed_and_is_small_at_the_papers_speed() -> None:
    subject = _subject(3)
    t = np.linspace(0.0, 20.0, 101)
    gaps = []
    for scale in (1.0, 4.0):
        base = human_arm_cell(subject=subject)
        spec = dataclasses.replace(base, trajectory=base.trajectory.speed_scaled(scale))
        dynamic = CellSimulator(dataclasses.replace(spec, inertia=True))
        static = CellSimulator(spec)
        tau_dyn = dynamic.inverse_dynamics_nm(t / scale)
        tau_static = static.inverse_dynamics_nm(t / scale)
        gaps.append(tau_dyn - tau_static)
        wrench_gap = dynamic.wrench_world(t / scale) - static.wrench_world(t / scale)
        # The wrench difference is exactly what carries the inertial torques through the Jacobian.
        jac = dynamic.contact_jacobian(t / scale)
        np.testing.assert_allclose(-np.einsum("nij,ni->nj", jac, wrench_gap), tau_dyn - tau_static, atol=1e-12)
        if scale == 1.0:  # NOTES: ~0.05 % of gravity at 0.03 rad/s
            assert np.abs(tau_dyn - tau_static).max() < 2e-3 * np.abs(tau_static).max()
    # Same poses (t / scale); velocities x scale and accelerations x scale^2: every inertial term x 16.
    np.testing.assert_allclose(gaps[1], 16.0 * gaps[0], rtol=1e-9, atol=1e-14)


def test_inertial_session_balances_pinocchio_torques_plus_passive_moment() -> None:
    """End to end: the sensor's wrench, turned back to world, carries rnea(q, q', q'') + tau_p."""
    subject = _subject(3)
    base = human_arm_cell(subject=subject, inertia=True, duration_s=4.0)
    spec = dataclasses.replace(
        base,
        trajectory=base.trajectory.speed_scaled(8.0),
        passive=PassiveTruth(coulomb_nm=(0.5, 0.28, 0.06), viscous_nms=(0.3, 0.1, 0.02)),
        sensor=dataclasses.replace(base.sensor, force_noise_n=0.0, torque_noise_nm=0.0, stamp_jitter_s=0.0),
    )
    sim = CellSimulator(spec)
    wrench = sim.sample_wrench(sim.wrench_stamps_ns())
    t = sim.seconds_since_start(wrench.t_ns)
    rot = sim.rotation_world_from_sensor
    f_world, m_world = wrench.force_n @ rot.T, wrench.torque_nm @ rot.T
    f_end = np.column_stack([f_world[:, 1], f_world[:, 2], m_world[:, 0]])
    model = _pinocchio_model(subject)
    data = model.createData()
    pin = pytest.importorskip("pinocchio")
    q, qd, qdd = sim.joint_angles_rad(t), sim.joint_velocities_rad_s(t), sim.joint_accelerations_rad_s2(t)
    rnea = np.array([pin.rnea(model, data, q[k], qd[k], qdd[k]) for k in range(t.size)])
    expected = rnea + sim.passive_torque_nm(t)
    np.testing.assert_allclose(-np.einsum("nij,ni->nj", sim.contact_jacobian(t), f_end), expected, atol=1e-9)


def test_quasi_static_session_equals_the_simulator_before_inertia() -> None:
    """With inertia off, the session is the one commit 3f2534c simulated (golden samples, same seeds)."""
    golden = json.loads(GOLDEN.read_text())
    human = human_arm_cell(
        seed=4,
        duration_s=6.0,
        inertia=False,
        passive=PassiveTruth(
            coulomb_nm=(0.5, 0.28, 0.06),
            viscous_nms=(0.8, 0.3, 0.1),
            stiffness_nm_per_rad=(0.2, 1.2, 0.05),
            neutral_rad=(-0.5, 1.87, 0.0),
            offset_nm=(0.1, -0.2, 0.03),
            friction_transition_rad_s=0.002,
        ),
    )
    human = dataclasses.replace(
        human,
        sensor=dataclasses.replace(
            human.sensor,
            force_bias_n=(0.3, -0.2, 0.1),
            force_drift_n_per_s=(0.01, 0, 0),
            handle_mass_kg=0.3,
            handle_com_m=(0.0, 0.01, 0.05),
            spike_fraction=0.01,
            stamp_jitter_s=2e-4,
        ),
        markers=dataclasses.replace(
            human.markers,
            skin_offset_m=((0.0, 0.01), (0.01, 0.0), (0.0, -0.01), (0.005, 0.005)),
            dropout_fraction=0.1,
            stamp_jitter_s=1e-4,
        ),
    )
    paper = paper_mechanical_arm_cell(seed=9, duration_s=6.0, inertia=False)
    cases: dict[str, CellSpec] = {"human": human, "paper": paper}
    for name, spec in cases.items():
        assert not spec.inertia  # quasi-static, as commit 3f2534c simulated (the core's default now has inertia)
        session = simulate_cell(spec).session
        want = golden[name]
        np.testing.assert_array_equal(session.wrench.t_ns[::7], want["wrench_t_ns"])
        np.testing.assert_allclose(session.wrench.force_n[::7], want["force_n"], rtol=0, atol=1e-12)
        np.testing.assert_allclose(session.wrench.torque_nm[::7], want["torque_nm"], rtol=0, atol=1e-12)
        for marker, series in session.markers.items():
            np.testing.assert_array_equal(series.t_ns[::5], want["markers"][marker]["t_ns"])
            np.testing.assert_allclose(series.position_m[::5], want["markers"][marker]["position_m"], atol=1e-15)


def test_anthropometric_inertias_come_from_the_table_and_the_paper_arm_is_a_slender_bar() -> None:
    subject = SubjectTruth.from_anthropometry("female", 62.0, 1.65, n_segments=3)
    for j, name in enumerate(subject.segment_names):
        want = inertia_com_kgm2("female", name, subject.masses_kg[j], subject.lengths_m[j])
        assert subject.inertia_com_kgm2[j] == pytest.approx(want, rel=1e-12)
    paper = SubjectTruth.paper_mechanical_arm()
    assert paper.inertia_com_kgm2 == pytest.approx([1.5 * 0.09 / 12, 1.16 * 0.09 / 12])


def test_truth_carries_the_inertia_groups_and_old_truth_files_still_load() -> None:
    subject = _subject(3)
    truth = CellSimulator(human_arm_cell(subject=subject, inertia=True)).truth
    data = json.loads(json.dumps(truth.to_dict()))
    m, a, l_, d, i_com = (
        np.array(v)
        for v in (
            subject.masses_kg,
            subject.lengths_m,
            subject.com_m,
            subject.com_perpendicular_m,
            subject.inertia_com_kgm2,
        )
    )
    about_joint = i_com + m * (l_**2 + d**2)
    grouped = about_joint + a**2 * np.array([m[1] + m[2], m[2], 0.0])
    for j, name in enumerate(truth.segment_names):
        seg = data["segments"][name]
        assert seg["inertia_com_kgm2"] == pytest.approx(i_com[j])
        assert seg["inertia_kgm2"] == pytest.approx(about_joint[j])
        assert seg["grouped_inertia_kgm2"] == pytest.approx(grouped[j])
        assert seg["perpendicular_moment_kgm"] == pytest.approx(m[j] * d[j])
    assert data["simulation"]["inertia"] is True
    back = SessionTruth.from_dict(data)
    assert back.subject == subject
    for seg in data["segments"].values():  # a truth.json written before inertias were simulated
        for key in ("inertia_com_kgm2", "inertia_kgm2", "grouped_inertia_kgm2", "perpendicular_moment_kgm"):
            del seg[key]
        del seg["com_perpendicular_m"]
    old = SessionTruth.from_dict(data)
    assert old.subject.com_perpendicular_m == (0.0, 0.0, 0.0)
    assert (
        old.subject.inertia_com_kgm2
        == SubjectTruth(subject.lengths_m, subject.masses_kg, subject.com_m).inertia_com_kgm2
    )
    assert all(math.isfinite(v) and v > 0 for v in old.subject.inertia_com_kgm2)


@pytest.mark.parametrize(
    ("field", "value", "named"),
    [
        ("inertia_com_kgm2", (0.02, -0.01, 0.001), "inertia_com_kgm2[1]"),
        ("inertia_com_kgm2", (0.02, 0.01), "inertia_com_kgm2 must have 3"),
        ("com_perpendicular_m", (0.0, 0.2, 0.0), "com_perpendicular_m[1]"),
    ],
)
def test_bad_inertia_or_offset_is_refused_naming_the_value(field: str, value: tuple, named: str) -> None:
    base = SubjectTruth.from_anthropometry()
    with pytest.raises(InputError, match=named.replace("[", r"\[").replace("]", r"\]")):
        dataclasses.replace(base, **{field: value})
