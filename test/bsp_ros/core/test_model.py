"""The arm model against finite differences and the simulator's independent physics."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import model
from bsp_ros.core import simulation as sim
from bsp_ros.errors import InputError


def test_jacobian_matches_finite_differences_of_the_contact_point() -> None:
    rng = np.random.default_rng(0)
    q = rng.uniform(-1.5, 1.5, size=(5, 3))
    lengths = np.array([0.29, 0.27, 0.09])
    jacobian = model.contact_jacobian(q, lengths)
    step = 1e-7
    for i in range(3):
        dq = q.copy()
        dq[:, i] += step
        moved = model.joint_positions_m(dq, lengths)[:, -1] - model.joint_positions_m(q, lengths)[:, -1]
        np.testing.assert_allclose(moved / step, jacobian[:, :2, i], atol=1e-6)
    np.testing.assert_array_equal(jacobian[:, 2, :], 1.0)


def test_contact_torques_balance_the_simulated_gravity() -> None:
    # The simulator computes gravity from masses and COM lever arms, not from this model's regressor.
    spec = dataclasses.replace(
        sim.human_arm_cell(seed=1, inertia=False), passive=sim.PassiveTruth(coulomb_nm=(0.0, 0.0, 0.0))
    )
    simulator = sim.CellSimulator(spec)
    t_s = np.linspace(0.0, 30.0, 50)
    q = simulator.joint_angles_rad(t_s)
    torques = model.contact_torques_nm(q, simulator.truth.lengths_m, simulator.wrench_world(t_s))
    gravity = model.gravity_regressor(q) @ np.array(simulator.truth.static_moments_kgm)
    np.testing.assert_allclose(torques, gravity, rtol=1e-10, atol=1e-12)


def test_static_moments_group_masses_as_the_contract_says() -> None:
    a, m, com = np.array([0.3, 0.27, 0.09]), np.array([2.0, 1.2, 0.45]), np.array([0.17, 0.12, 0.07])
    beta = model.static_moments_kgm(a, m, com)
    expected = [m[0] * com[0] + a[0] * (m[1] + m[2]), m[1] * com[1] + a[1] * m[2], m[2] * com[2]]
    np.testing.assert_allclose(beta, expected)


def test_static_moments_jacobian_matches_finite_differences() -> None:
    a, x = np.array([0.3, 0.27, 0.09]), np.array([2.0, 1.2, 0.45, 0.17, 0.12, 0.07])
    jac = model.static_moments_jacobian(a, x[:3], x[3:])
    for k in range(6):
        dx = x.copy()
        dx[k] += 1e-7
        diff = (model.static_moments_kgm(a, dx[:3], dx[3:]) - model.static_moments_kgm(a, x[:3], x[3:])) / 1e-7
        np.testing.assert_allclose(diff, jac[:, k], atol=1e-6)


@pytest.mark.parametrize("lengths", [[0.3], [0.3, -0.2], [0.3, np.nan], [0.3, 2.0]])
def test_silly_lengths_are_refused_with_the_value_named(lengths) -> None:
    with pytest.raises(InputError, match="length"):
        model.check_lengths_m(lengths)


def test_one_sample_torques_and_regressor_match_the_array_versions() -> None:
    from bsp_ros.core.model import contact_torques_nm, contact_torques_one_nm, gravity_regressor, gravity_regressor_one

    rng = np.random.default_rng(21)
    for n in (2, 3):
        q, wrench = rng.normal(size=n), rng.normal(size=3)
        lengths = rng.uniform(0.1, 0.4, size=n)
        np.testing.assert_allclose(
            contact_torques_one_nm(q, lengths, wrench),
            contact_torques_nm(q[None], lengths, wrench[None])[0],
            atol=1e-12,
        )
        np.testing.assert_allclose(gravity_regressor_one(q), gravity_regressor(q[None])[0], atol=1e-12)


def test_running_sum_gives_numpys_cumsum_bit_for_bit() -> None:
    rng = np.random.default_rng(5)
    flat, points = rng.normal(size=(500, 3)), rng.normal(size=(500, 3, 2))
    assert np.array_equal(model.running_sum(flat), np.cumsum(flat, axis=1))
    assert np.array_equal(model.running_sum(points), np.cumsum(points, axis=1))
    assert np.array_equal(model.running_sum(flat, reverse=True), np.cumsum(flat[:, ::-1], axis=1)[:, ::-1])
