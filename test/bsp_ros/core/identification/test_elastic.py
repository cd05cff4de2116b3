"""Elastic terms beyond a linear spring: a conservative field, curves that match the columns, and auto on a sim."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.elastic import (
    CURVE_POINTS,
    ElasticReference,
    curve_angles_rad,
    curve_gradients,
    elastic_columns,
    elastic_names,
)
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.errors import InputError

TERMS = ("nonlinear", "coupling")


def _reference(rng: np.random.Generator, n: int = 3) -> ElasticReference:
    q = rng.uniform(-0.6, 0.6, size=(500, n)) + np.array([-0.5, 0.8, 0.1])[:n]
    return ElasticReference.from_angles(q)


@pytest.mark.parametrize("terms", [TERMS, (*TERMS, "higher")])
def test_the_elastic_moments_are_the_gradient_of_a_potential(terms: tuple[str, ...]) -> None:
    """A passive elastic field (muscles, tendons, skin) is conservative: its stiffness matrix d tau_i / d q_j is
    symmetric. Checked by central differences at random postures for random coefficients; ``higher`` (the shape
    probe's next order) too."""
    rng = np.random.default_rng(7)
    reference = _reference(rng)
    theta = rng.normal(size=len(elastic_names(terms, 3)))
    assert elastic_columns(reference.centre_rad[None, :], terms, reference).shape[2] == theta.size
    step = 1e-6
    for _ in range(5):
        q = rng.uniform(-1.0, 1.0, size=3)
        jacobian = np.empty((3, 3))
        for j in range(3):
            dq = np.zeros(3)
            dq[j] = step
            plus = elastic_columns((q + dq)[None, :], terms, reference)[0] @ theta
            minus = elastic_columns((q - dq)[None, :], terms, reference)[0] @ theta
            jacobian[:, j] = (plus - minus) / (2 * step)
        np.testing.assert_allclose(jacobian, jacobian.T, atol=1e-6)
        assert np.abs(jacobian[0, 1]) > 1e-3  # the coupling is really there


def test_a_curve_is_the_columns_evaluated_with_the_other_joints_at_their_means() -> None:
    rng = np.random.default_rng(3)
    reference = _reference(rng)
    names = [("offset_nm", "elbow"), ("stiffness_nm_per_rad", "elbow"), *elastic_names(TERMS, 3)]
    theta = rng.normal(size=len(names))
    gradients = curve_gradients(names, TERMS, reference)
    angles = curve_angles_rad(reference)[1]
    q = np.repeat(reference.mean_rad[None, :], CURVE_POINTS, axis=0)
    q[:, 1] = angles
    direct = theta[0] + theta[1] * angles + elastic_columns(q, TERMS, reference)[:, 1, :] @ theta[2:]
    np.testing.assert_allclose(gradients[1, :CURVE_POINTS] @ theta, direct, rtol=1e-12, atol=1e-12)


def test_elastic_terms_extend_a_linear_spring_only() -> None:
    with pytest.raises(InputError, match="needs 'offset\\+stiffness'"):
        PassiveModel.parse("coulomb+coupling")
    with pytest.raises(InputError, match="or 'auto', got \\('automatic',\\)"):
        PassiveModel.parse("automatic")
    assert PassiveModel.parse("auto").select
    assert PassiveModel.parse("auto").candidates()[-1].label == "coulomb+offset+stiffness+nonlinear+coupling"
    # The shape probe's next order extends the nonlinear terms, never a linear spring alone.
    with pytest.raises(InputError, match="a higher term extends the nonlinear one: it needs 'nonlinear' too"):
        PassiveModel.parse("coulomb+offset+stiffness+higher")
    assert "higher" in PassiveModel.parse("coulomb+offset+stiffness+nonlinear+higher").elastic


@pytest.fixture(scope="module")
def spring_session() -> tuple[object, dict]:
    """Our simulator's arm with linear springs at the shoulder and elbow, 60 s of the default protocol."""
    passive = sim.PassiveTruth(
        coulomb_nm=(0.5, 0.28, 0.06), stiffness_nm_per_rad=(0.3, 0.5, 0.0), offset_nm=(0.1, 0.2, 0.0)
    )
    simulated = sim.simulate_cell(sim.human_arm_cell(seed=5, duration_s=60.0, passive=passive))
    return identification_data_from_session(simulated.session), simulated.truth.to_dict()


def test_auto_holds_the_truth_within_its_std_and_reports_curves(spring_session) -> None:
    data, truth = spring_session
    result = identify_joint(data, JointConfig(passive=PassiveModel.parse("auto")))
    assert result.valid, result.message
    assert "offset" in result.diagnostics["passive_model"]  # the springs are not left out
    for (key, owner), value, std in zip(result.names, result.values, result.std, strict=True):
        group = "segments" if owner in truth["segments"] else "joints"
        true = truth[group].get(owner, {}).get(key)
        if key in ("static_moment_kgm", "coulomb_nm") and true is not None:
            assert abs(value - true) <= 3 * std, (key, owner, value, true, std)
    curves = result.diagnostics["passive_curves"]
    elbow = curves["elbow"]
    angles = np.radians(elbow["angle_deg"])
    true_curve = 0.2 + 0.5 * angles  # the simulator's spring: offset + k q (neutral 0)
    z = (np.array(elbow["moment_nm"]) - true_curve) / np.array(elbow["std_nm"])
    assert np.abs(z).max() < 3, z
