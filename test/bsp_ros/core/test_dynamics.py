"""The base regressor against pinocchio's recursive Newton-Euler on the same planar chain."""

from __future__ import annotations

import numpy as np
import pytest
from pinocchio_chain import planar_chain

from bsp_ros.core.dynamics import base_parameters, base_regressor, base_regressor_one, base_torque_angle_derivatives
from bsp_ros.core.model import gravity_regressor

pin = pytest.importorskip("pinocchio", reason="pinocchio (pip 'pin') is the independent rigid-body oracle")


@pytest.mark.parametrize("n", [2, 3])
def test_base_regressor_equals_pinocchio_rnea(n):
    rng = np.random.default_rng(7)
    lengths = np.array([0.29, 0.27, 0.09])[:n]
    masses = np.array([2.1, 1.3, 0.45])[:n]
    com = np.array([0.16, 0.12, 0.06])[:n]
    com_normal = np.array([0.004, -0.006, 0.003])[:n]
    inertia = np.array([0.015, 0.008, 0.0012])[:n]
    model = planar_chain(pin, lengths, masses, com, com_normal, inertia)
    data = model.createData()
    q, qd, qdd = rng.uniform(-1.5, 1.5, (3, 50, n)) * np.array([1.0, 0.8, 3.0])[:, None, None]
    theta = base_parameters(lengths, masses, com, inertia, com_normal)
    ours = base_regressor(q, qd, qdd, lengths) @ theta
    theirs = np.array([pin.rnea(model, data, q[t], qd[t], qdd[t]) for t in range(q.shape[0])])
    np.testing.assert_allclose(ours, theirs, atol=1e-10)
    # The live filter's one-sample version in plain floats: the same bits as the vectorised one.
    one = np.array([base_regressor_one(q[t], qd[t], qdd[t], lengths) for t in range(q.shape[0])])
    assert np.array_equal(one, base_regressor(q, qd, qdd, lengths))


def test_static_columns_are_the_gravity_regressor():
    q = np.random.default_rng(3).uniform(-1, 1, (20, 3))
    zeros = np.zeros_like(q)
    np.testing.assert_allclose(base_regressor(q, zeros, zeros, [0.3, 0.3, 0.1])[:, :, :3], gravity_regressor(q))


@pytest.mark.parametrize("n", [2, 3])
def test_closed_form_angle_derivatives_match_central_differences(n: int) -> None:
    rng = np.random.default_rng(11 + n)
    q, qd, qdd = (rng.normal(scale=0.8, size=(40, n)) for _ in range(3))
    lengths, base = rng.uniform(0.2, 0.4, n), rng.normal(size=3 * n)
    derivative = base_torque_angle_derivatives(q, qd, qdd, lengths, base)
    step = 1e-6
    for s in range(n):
        turn = np.zeros(n)
        turn[s] = step
        if s + 1 < n:
            turn[s + 1] = -step  # the absolute angle of segment s alone
        numeric = (
            base_regressor(q + turn, qd, qdd, lengths) @ base - base_regressor(q - turn, qd, qdd, lengths) @ base
        ) / (2 * step)
        np.testing.assert_allclose(derivative[:, :, s], numeric, atol=1e-7 * np.abs(numeric).max())
