"""The covariance ledger: named terms whose sum is the estimate's covariance, on simulated sessions."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.joint.refit import refit_held
from bsp_ros.core.identification.ledger import Ledger, Term
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.result import IdentificationResult


@pytest.fixture(scope="module")
def data() -> IdentificationData:
    subject = sim.SubjectTruth.from_anthropometry("male", 75.0, 1.78, 3, rng=np.random.default_rng(7))
    return identification_data_from_session(
        sim.simulate_cell(sim.human_arm_cell(subject=subject, seed=7, duration_s=60.0)).session
    )


def _sums_to_its_covariance(result: IdentificationResult) -> None:
    assert result.ledger is not None
    np.testing.assert_allclose(result.ledger.total(len(result.names)), result.covariance, rtol=1e-12, atol=1e-300)
    for i in range(len(result.names)):
        parts = result.budget(i)
        assert sum(u**2 for u in parts.values()) == pytest.approx(result.covariance[i, i], rel=1e-9)


def test_terms_add_replace_and_sum() -> None:
    a, b = np.diag([1.0, 4.0]), np.diag([9.0, 0.0])
    ledger = Ledger.of(Term.SENSOR_NOISE, a).plus(Term.MARKER_PLACEMENT, b).plus(Term.MARKER_PLACEMENT, b)
    np.testing.assert_array_equal(ledger.total(2), a + 2 * b)
    assert ledger.contributions(0) == {"sensor_noise": 1.0, "marker_placement": pytest.approx(np.sqrt(18.0))}
    replaced = ledger.with_term(Term.MARKER_PLACEMENT, b)
    np.testing.assert_array_equal(replaced.total(2), a + b)
    assert [t for t, _ in replaced.without(Term.SENSOR_NOISE)] == [Term.MARKER_PLACEMENT]
    assert [t for t, _ in Ledger.of(Term.DRIFT, a).joined(replaced)] == [
        Term.DRIFT,
        Term.SENSOR_NOISE,
        Term.MARKER_PLACEMENT,
    ]


def test_exact_markers_leave_the_sensor_noise_and_the_friction_shape(data: IdentificationData) -> None:
    result = identify_joint(data, JointConfig(marker_placement_sd_m=0.0, handle_pose_sd_m=0.0))
    assert result.ledger is not None and [t for t, _ in result.ledger] == [Term.SENSOR_NOISE, Term.FRICTION_SHAPE]
    shape = result.ledger.get(Term.FRICTION_SHAPE)
    assert shape is not None
    coulomb = [i for i, (key, _) in enumerate(result.names) if key == "coulomb_nm"]
    others = np.setdiff1d(np.arange(len(result.names)), coulomb)
    assert not shape[np.ix_(others, others)].any() and shape[coulomb, coulomb].any()  # Coulomb amplitudes only
    _sums_to_its_covariance(result)


def test_the_placement_term_is_the_share_the_assumed_placement_adds(data: IdentificationData) -> None:
    exact = identify_joint(data, JointConfig(marker_placement_sd_m=0.0))
    placed = identify_joint(data, JointConfig())
    assert placed.ledger is not None and Term.MARKER_PLACEMENT in placed.ledger
    _sums_to_its_covariance(placed)
    # The fit is the same: the placement adds its share and nothing else.
    np.testing.assert_allclose(placed.values, exact.values, rtol=1e-12)
    assert exact.ledger is not None and Term.MARKER_PLACEMENT not in exact.ledger
    sensor, exact_sensor = placed.ledger.get(Term.SENSOR_NOISE), exact.ledger.get(Term.SENSOR_NOISE)
    assert sensor is not None and exact_sensor is not None
    # The noise term is the sandwich of the residual the offsets leave: on markers that sit on their centres,
    # about the raw residual's.
    np.testing.assert_allclose(np.diag(sensor), np.diag(exact_sensor), rtol=0.05)
    beta = placed.index("static_moment_kgm", "forearm")
    assert placed.budget(beta)["marker_placement"] > placed.budget(beta)["sensor_noise"]  # 2 mm dominates


def test_a_drift_and_a_data_chosen_model_are_their_own_terms(data: IdentificationData) -> None:
    spec = sim.human_arm_cell(seed=2, duration_s=60.0)
    sensor = dataclasses.replace(spec.sensor, force_drift_n_per_s=(0.0, 0.007, 0.007))
    drifting = identification_data_from_session(sim.simulate_cell(dataclasses.replace(spec, sensor=sensor)).session)
    drift = identify_joint(drifting, JointConfig(marker_placement_sd_m=0.0))
    assert drift.ledger is not None and Term.DRIFT in drift.ledger, drift.warnings
    _sums_to_its_covariance(drift)
    auto = identify_joint(data, JointConfig(passive=PassiveModel.parse("auto")))
    assert auto.ledger is not None and Term.MODEL_CHOICE in auto.ledger
    _sums_to_its_covariance(auto)


def test_a_refit_keeps_the_systematic_terms_and_takes_its_own_noise_and_placement(data: IdentificationData) -> None:
    checked = identify_joint(data, JointConfig(passive=PassiveModel.parse("auto")))
    assert checked.held is not None and checked.ledger is not None
    later = refit_held(data.window(1000, data.t_ns.size), checked.held, JointConfig())
    assert later.ledger is not None
    assert {t for t, _ in later.ledger} == {t for t, _ in checked.ledger}
    np.testing.assert_array_equal(later.ledger.get(Term.MODEL_CHOICE), checked.ledger.get(Term.MODEL_CHOICE))
    _sums_to_its_covariance(later)


def test_a_term_added_to_a_result_joins_its_covariance_and_budget(data: IdentificationData) -> None:
    result = identify_joint(data, JointConfig())
    zero = np.diag(np.full(len(result.names), 1e-6))
    tared = result.plus_term(Term.SENSOR_ZERO, zero)
    np.testing.assert_allclose(tared.covariance, result.covariance + zero)
    assert tared.budget(0)["sensor_zero"] == pytest.approx(1e-3)
    _sums_to_its_covariance(tared)
