"""The stacked problem's regressor blocks (an augmented problem joins its columns only when a pass needs them) and
its per-sample scores."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig
from bsp_ros.core.identification.joint.samples import usable_samples
from bsp_ros.core.identification.stacked import augmented, fit_problem, joint_scores, reweighted_values


def test_an_augmented_problem_solves_from_its_blocks_as_from_the_joined_regressor(human_session) -> None:
    data = identification_data_from_session(human_session.session)
    problem = usable_samples(data, JointConfig(marker_placement_sd_m=0.0)).problem
    rng = np.random.default_rng(7)
    extra = rng.normal(size=(data.t_ns.size, data.n_joints, 2))
    wide = augmented(problem, extra, [("extra_a", "test"), ("extra_b", "test")])
    assert len(wide.blocks) == 2 and wide.blocks[0] is problem.regressor  # nothing copied
    solved = reweighted_values(wide)
    residual = solved.residual(wide)  # from the blocks
    assert "regressor" not in wide.__dict__  # the values and the residual never joined them
    joined = np.concatenate((problem.regressor, extra), axis=2)
    np.testing.assert_allclose(residual, wide.torque - joined @ solved.values, rtol=0, atol=1e-12)
    fit = fit_problem(wide, solved)  # the covariance's scores pass over the joined columns
    np.testing.assert_array_equal(wide.regressor, joined)
    assert fit.values.shape == (len(problem.names) + 2,)


def test_joint_scores_sum_each_joints_regressor_row_times_its_weighted_residual() -> None:
    rng = np.random.default_rng(3)
    regressor = rng.normal(size=(500, 3, 7))
    weighted = rng.normal(size=(500, 3))
    weighted[::7, 1] = 0.0  # rows a joint does not use
    expected = np.zeros((500, 7))
    for t in range(500):
        for i in range(3):
            expected[t] += regressor[t, i] * weighted[t, i]
    np.testing.assert_allclose(joint_scores(regressor, weighted), expected, rtol=1e-13, atol=1e-13)
