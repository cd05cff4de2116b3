"""The stacked problem's per-joint columns (0 off a joint's used rows; an augmented problem joins its blocks only
when a pass needs them) against the dense (N, n, p) regressor built from the model's own functions, and its
per-sample scores and products."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.elastic import ElasticReference, elastic_columns
from bsp_ros.core.identification.joint import JointConfig
from bsp_ros.core.identification.joint.samples import usable_samples
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.stacked import (
    Problem,
    augmented,
    build_problem,
    fit_problem,
    joint_products,
    joint_scores,
    reweighted_values,
)
from bsp_ros.core.model import gravity_regressor


def _dense(problem: Problem) -> np.ndarray:
    """(N, n, p) the problem's regressor stacked, its blocks joined, 0 off each joint's used rows."""
    n = problem.torque.shape[1]
    return np.stack([np.hstack([block[j] for block in problem.blocks]) for j in range(n)], axis=1)


@pytest.mark.parametrize(
    "terms",
    [("coulomb",), ("coulomb", "viscous", "offset", "stiffness"), ("coulomb", "offset", "stiffness", "nonlinear")],
)
def test_each_joints_columns_are_the_gravity_regressors_row_and_its_passive_terms_on_its_used_rows(
    human_session, terms
) -> None:
    data = identification_data_from_session(human_session.session)
    n, passive = data.n_joints, PassiveModel(terms)
    rows = np.random.default_rng(5).random(data.tau_nm.shape) > 0.2  # a fifth of each joint's rows unused
    widths = np.array([0.0, 0.02, 0.0])
    problem = build_problem(data, passive, rows, widths)
    dense, k = _dense(problem), len(passive.local)
    expected = np.zeros_like(dense)
    expected[:, :, :n] = gravity_regressor(data.q_rad)
    for j in range(n):
        expected[:, j, n + j * k : n + (j + 1) * k] = passive.columns(data.passive_q_rad, data.velocity_rad_s, j)
    column = n + 1 * k + passive.local.index("coulomb")
    expected[:, 1, column] = np.tanh(data.velocity_rad_s[:, 1] / 0.02)
    if passive.elastic:
        reference = ElasticReference.from_angles(data.passive_q_rad)
        expected[:, :, n + n * k :] = elastic_columns(data.passive_q_rad, passive.elastic, reference)
    expected[~rows] = 0.0
    np.testing.assert_array_equal(dense, expected)
    for j in range(n):
        np.testing.assert_array_equal(problem.joint_rows(j)[1], np.where(rows[:, j], data.tau_nm[:, j], 0.0))


def test_an_augmented_problem_solves_from_its_blocks_as_from_the_joined_regressor(human_session) -> None:
    data = identification_data_from_session(human_session.session)
    problem = usable_samples(data, JointConfig(marker_placement_sd_m=0.0)).problem
    rng = np.random.default_rng(7)
    extra = rng.normal(size=(data.t_ns.size, data.n_joints, 2))
    wide = augmented(problem, extra, [("extra_a", "test"), ("extra_b", "test")])
    assert len(wide.blocks) == 2 and wide.blocks[0] is problem.blocks[0]  # nothing copied
    solved = reweighted_values(wide)
    residual = solved.residual(wide)  # from the blocks
    assert not any(wide.regressors.joined(j) for j in range(data.n_joints))  # the values and residual never joined them
    joined = np.concatenate((_dense(problem), np.where(problem.rows[..., None], extra, 0.0)), axis=2)
    expected = np.where(problem.rows, wide.torque - joined @ solved.values, 0.0)
    np.testing.assert_allclose(residual, expected, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(_dense(wide), joined)
    fit = fit_problem(wide, solved)
    assert fit.values.shape == (len(problem.names) + 2,)
    assert np.isnan(fit.residual[~problem.rows]).all() and np.isfinite(fit.residual[problem.rows]).all()


def test_joint_scores_and_products_sum_each_joints_rows_as_the_dense_regressor_does(human_session) -> None:
    data = identification_data_from_session(human_session.session)
    problem = usable_samples(data, JointConfig(marker_placement_sd_m=0.0)).problem
    rng = np.random.default_rng(3)
    wide = augmented(problem, rng.normal(size=(data.t_ns.size, data.n_joints, 3)), [("e", str(i)) for i in range(3)])
    dense = _dense(wide)  # (N, n, p), 0 off the used rows
    weighted = np.where(wide.rows, rng.normal(size=wide.torque.shape), 0.0)
    expected = np.einsum("tip,ti->tp", dense, weighted)
    np.testing.assert_allclose(joint_scores(wide, weighted), expected, rtol=1e-12, atol=1e-12)
    projection = rng.normal(size=(len(wide.names), 4))
    np.testing.assert_allclose(joint_scores(wide, weighted, projection), expected @ projection, rtol=1e-10, atol=1e-9)
    weights, b = np.array([1.0, 4.0, 9.0]), rng.normal(size=(data.t_ns.size, data.n_joints, 2))
    products = np.einsum("tip,i,tim->pm", dense, weights, b)
    np.testing.assert_allclose(joint_products(wide, weights, b), products, rtol=1e-10, atol=1e-9)
    np.testing.assert_allclose(joint_products(wide, weights, b[:, :, 0]), products[:, 0], rtol=1e-10, atol=1e-9)
