"""The placement term with the fit's per-joint weights following the offsets, against the estimator itself refitted
on torques that offsets drawn from the placement prior move."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.placement_covariance import (
    covariance_from_columns,
    offset_columns,
    offset_names,
)
from bsp_ros.core.identification.joint.placement_reweighting import (
    OffsetStatistics,
    reweighted_placement_covariance,
    used_variance,
)
from bsp_ros.core.identification.joint.samples import usable_samples
from bsp_ros.core.identification.stacked import Problem, augmented, fit_problem, reweighted_values

SD_M = np.full(4, 0.004)


@functools.cache
def _fast_session() -> IdentificationData:
    """The human arm cell on its sines four times faster, quiet sensor: the handle force's dynamic part on an
    offset lever leaves residuals no parameter takes up, several times the noise."""
    spec = sim.human_arm_cell(seed=4, duration_s=60.0)
    trajectory = spec.trajectory
    assert isinstance(trajectory, sim.TrajectorySpec)
    fast = dataclasses.replace(trajectory, period_s=tuple(p / 4.0 for p in trajectory.period_s))
    sensor = dataclasses.replace(spec.sensor, force_noise_n=0.01, torque_noise_nm=0.001)
    return identification_data_from_session(
        sim.simulate_cell(dataclasses.replace(spec, trajectory=fast, sensor=sensor)).session
    )


def _statistics(problem: Problem, columns: np.ndarray) -> OffsetStatistics:
    m = columns.shape[2]
    wider = augmented(problem, columns, offset_names(m), np.zeros(m), np.ones(m))
    assert wider.statistics is not None
    base = used_variance(problem, reweighted_values(wider).residual(wider))
    return OffsetStatistics.of(problem, wider.statistics, base, np.ones(problem.torque.shape[1]))


def _refitted_spread(data: IdentificationData, columns: np.ndarray, draws: int) -> np.ndarray:
    """(p,) the std of the estimator's values over offsets drawn from the prior (seeded), the torques moved by
    their columns and the whole reweighted fit run on each: an independent route to the term."""
    config = JointConfig()
    base = reweighted_values(usable_samples(data, config).problem).values
    rng = np.random.default_rng(1)
    changes = []
    for _ in range(draws):
        offsets = rng.standard_normal(columns.shape[2])
        moved = dataclasses.replace(data, tau_nm=data.tau_nm + columns @ offsets)
        changes.append(reweighted_values(usable_samples(moved, config).problem).values - base)
    return np.asarray(np.sqrt(np.mean(np.square(changes), axis=0)))


def test_the_term_follows_the_weights_as_the_refitted_estimator_does() -> None:
    data = _fast_session()
    problem = usable_samples(data, JointConfig()).problem
    fit = fit_problem(problem)
    columns = offset_columns(data, problem, fit, SD_M)
    term = np.sqrt(np.diag(reweighted_placement_covariance(_statistics(problem, columns))))
    linear = np.sqrt(np.diag(covariance_from_columns(problem, fit, columns)))
    refitted = _refitted_spread(data, columns, 160)
    static = slice(0, 3)  # the static moments; the linear response at the fit's weights was 1.3-2.4 times too wide
    np.testing.assert_allclose(term[static], refitted[static], rtol=0.15)
    assert np.max(np.abs(linear[static] / refitted[static] - 1.0)) > 0.25


def test_where_the_offsets_leave_no_residual_the_term_is_the_linear_one() -> None:
    # Offsets whose columns the parameters take up entirely move no joint's weight: the term is G G^T (to the
    # rounding of the residual they leave, 0).
    data = _fast_session()
    problem = usable_samples(data, JointConfig()).problem
    fit = fit_problem(problem)
    regressor = np.stack(
        [np.concatenate([block[j] for block in problem.blocks], axis=1) for j in range(data.n_joints)], axis=1
    )
    mixing = np.random.default_rng(3).standard_normal((regressor.shape[2], 5)) * 1e-3
    columns = regressor @ mixing
    statistics = _statistics(problem, columns)
    statistics = dataclasses.replace(statistics, base_variance=fit.sigma**2)
    term = reweighted_placement_covariance(statistics)
    linear = covariance_from_columns(problem, fit, columns)
    np.testing.assert_allclose(np.diag(term), np.diag(linear), rtol=1e-3)


def test_with_each_session_s_residual_variances_the_term_holds_its_error() -> None:
    # Each drawn session's own per-joint residual variances tell how far its offsets took the weights: the term is
    # what the draws that match them give where that is clearly more than the prior's mean, against the error the
    # refitted estimator made in that session.
    data = _fast_session()
    config = JointConfig()
    problem = usable_samples(data, config).problem
    fit = fit_problem(problem)
    columns = offset_columns(data, problem, fit, SD_M)
    statistics = _statistics(problem, columns)
    prior = np.sqrt(np.diag(reweighted_placement_covariance(statistics)))[:3]
    base = reweighted_values(problem).values
    rng = np.random.default_rng(2)
    z, widened = [], 0
    for _ in range(60):
        moved = dataclasses.replace(data, tau_nm=data.tau_nm + columns @ rng.standard_normal(columns.shape[2]))
        solved = reweighted_values(usable_samples(moved, config).problem)
        session = dataclasses.replace(statistics, observed_variance=solved.sigma**2)
        std = np.sqrt(np.diag(reweighted_placement_covariance(session)))[:3]
        assert np.all(std >= prior * (1.0 - 1e-9))
        widened += bool(np.any(std > 1.4 * prior))
        z.append((solved.values[:3] - base[:3]) / std)
    z_rms = np.sqrt(np.mean(np.square(z), axis=0))
    assert np.all((z_rms > 0.7) & (z_rms < 1.3)), z_rms  # the acceptance's band; 60 sessions scatter it by 9 %
    assert np.abs(z).max() < 3.0
    assert widened > 2  # some sessions' offsets took a joint's weight away, and their std says so


def test_a_parameter_no_data_or_prior_holds_gets_no_response_and_no_failure() -> None:
    # A session too short for its model (a 4 s MuJoCo session fitted with stiffness left the design singular):
    # the term is finite, 0 (to rounding) along the parameter nothing holds, and unchanged elsewhere in size.
    data = _fast_session()
    problem = usable_samples(data, JointConfig()).problem
    fit = fit_problem(problem)
    statistics = _statistics(problem, offset_columns(data, problem, fit, SD_M))
    held = np.sqrt(np.diag(reweighted_placement_covariance(statistics)))
    free = 1  # the forearm's static moment, its columns and its prior taken away
    gram, cross = statistics.gram.copy(), statistics.cross.copy()
    gram[:, free, :] = 0.0
    gram[:, :, free] = 0.0
    cross[:, free, :] = 0.0
    precision = statistics.prior_precision.copy()
    precision[free] = 0.0
    singular = dataclasses.replace(statistics, gram=gram, cross=cross, prior_precision=precision)
    term = np.sqrt(np.diag(reweighted_placement_covariance(singular)))
    assert np.all(np.isfinite(term)) and term[free] < 1e-5 * held.max()
    assert np.all(term[[0, 2]] > 0.1 * held[[0, 2]])
