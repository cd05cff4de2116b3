"""The weight support wrench against J^T F = s tau_G, hand-worked poses and linear uncertainty propagation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bsp_ros.core import model
from bsp_ros.core.weight_support import SingularPoseError, estimate_from_result, live_support, support_wrench
from bsp_ros.errors import InputError

G = 9.81


@pytest.mark.parametrize("n", [2, 3])
def test_jacobian_transpose_of_support_equals_fraction_of_gravity(n: int) -> None:
    rng = np.random.default_rng(12)
    lengths = np.array([0.30, 0.27, 0.09])[:n]
    beta = np.array([0.9, 0.25, 0.04])[:n]
    for _ in range(20):
        q = rng.uniform(-1.2, 1.2, size=n)
        q[1] = rng.uniform(0.2, 2.5)  # away from the straight/folded arm
        s = float(rng.uniform(0.0, 1.0))
        support = support_wrench(q, lengths, beta, s)
        jacobian = model.contact_jacobian(q[None, :], lengths)[0]
        tau_g = model.gravity_regressor(q[None, :])[0] @ beta
        np.testing.assert_allclose(jacobian.T @ support.wrench_yzx, s * tau_g, rtol=0, atol=1e-9)
        if n == 2:
            assert support.wrench_yzx[2] == 0.0


def test_two_segment_pose_worked_by_hand() -> None:
    # Upper arm forward (q1 = 0), forearm straight up (q2 = 90 deg), a1 = a2 = 0.3 m, beta = (0.6, 0.2) kg m.
    # tau_G = g (0.6 cos 0 + 0.2 cos 90, 0.2 cos 90) = (0.6 g, 0).
    # J^T F: shoulder -0.3 F_y + 0.3 F_z, elbow -0.3 F_y (+ 0 F_z). With s = 0.5: F_y = 0, F_z = 0.5 * 0.6 g / 0.3 = g.
    support = support_wrench([0.0, math.pi / 2], [0.3, 0.3], [0.6, 0.2], 0.5)
    np.testing.assert_allclose(support.wrench_yzx, [0.0, 9.81, 0.0], atol=1e-12)


def test_three_segment_pose_worked_by_hand() -> None:
    # q = (0, 90, -90) deg: upper arm forward, forearm up, hand forward; a = (0.3, 0.25, 0.1) m,
    # beta = (0.5, 0.2, 0.05) kg m. tau_G = g (0.5 + 0.05, 0.05, 0.05).
    # J columns (dy, dz, 1): (-0.25, 0.4, 1), (-0.25, 0.1, 1), (0, 0.1, 1).
    # Rows 2 - 3: -0.25 F_y = 0 -> F_y = 0; rows 1 - 2: 0.3 F_z = 0.5 g -> F_z = 16.35 N;
    # row 3: M_x = 0.05 g - 0.1 F_z = 0.4905 - 1.635 = -1.1445 Nm.
    support = support_wrench([0.0, math.pi / 2, -math.pi / 2], [0.3, 0.25, 0.1], [0.5, 0.2, 0.05], 1.0)
    np.testing.assert_allclose(support.wrench_yzx, [0.0, 16.35, -1.1445], atol=1e-12)


def test_uncertainty_is_the_linear_propagation_of_the_static_moments() -> None:
    rng = np.random.default_rng(3)
    q, lengths, beta = np.array([-0.7, 0.6, 0.1]), np.array([0.29, 0.27, 0.09]), np.array([1.0, 0.3, 0.04])
    root = rng.normal(size=(3, 3)) * 0.01
    covariance = root @ root.T
    support = support_wrench(q, lengths, beta, 0.6, covariance)
    draws = rng.multivariate_normal(beta, covariance, size=2000)
    sampled = np.array([support_wrench(q, lengths, b, 0.6).wrench_yzx for b in draws])
    np.testing.assert_allclose(sampled.std(axis=0), support.std, rtol=0.08)


def test_straight_arm_is_refused_with_the_reason() -> None:
    with pytest.raises(SingularPoseError, match="straight or folded"):
        support_wrench([-0.5, math.radians(2.0), 0.0], [0.3, 0.27, 0.09], [1.0, 0.3, 0.04], 1.0)


def test_bad_fraction_is_refused() -> None:
    with pytest.raises(InputError, match="support_fraction"):
        support_wrench([-0.5, 1.0], [0.3, 0.3], [1.0, 0.3], 1.5)


def test_live_support_publishes_only_for_a_valid_estimate() -> None:
    estimate = {"valid": True, "static_moments_kgm": [0.6, 0.2], "covariance": np.diag([1e-4, 1e-5])}
    decision = live_support(estimate, [0.0, math.pi / 2], [0.3, 0.3], 0.5)
    assert decision.wrench is not None
    np.testing.assert_allclose(decision.wrench.wrench_yzx, [0.0, 9.81, 0.0], atol=1e-12)
    assert live_support({**estimate, "valid": False}, [0.0, 1.0], [0.3, 0.3], 0.5).wrench is None
    assert live_support(None, [0.0, 1.0], [0.3, 0.3], 0.5).wrench is None
    straight = live_support(estimate, [0.0, 0.0], [0.3, 0.3], 0.5)
    assert straight.wrench is None and "straight" in straight.reason


def test_live_support_from_an_identification_and_its_diagnostics() -> None:
    from bsp_ros.core.identification.data import identification_data_from_session
    from bsp_ros.core.identification.joint import identify_joint
    from bsp_ros.core.simulation import paper_mechanical_arm_cell, simulate_cell

    simulated = simulate_cell(paper_mechanical_arm_cell(duration_s=60.0, seed=2))
    result = identify_joint(identification_data_from_session(simulated.session))
    q, lengths = [-0.6, 0.6], simulated.truth.lengths_m
    decision = live_support(estimate_from_result(result), q, lengths, 1.0)
    assert decision.wrench is not None
    exact = support_wrench(q, lengths, simulated.truth.static_moments_kgm, 1.0).wrench_yzx
    # The identified static moments carry the truth within 3 std, and so does the wrench.
    assert (np.abs(decision.wrench.wrench_yzx - exact)[:2] < 3 * decision.wrench.std[:2] + 1e-9).all()
    diagnostics = decision.diagnostics()
    assert set(diagnostics) >= {"reason", "F_y_N", "F_y_N_std", "F_z_N", "F_z_N_std", "M_x_Nm", "support_fraction"}
