"""An elastic finding names, in ``values["passive_option"]``, the ``--passive`` model that takes its spring up."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.passive import PassiveModel

# An elbow spring the default (Coulomb) model lacks: the elastic check finds it (as in test_finding_codes).
SPRING = sim.PassiveTruth(
    coulomb_nm=(0.5, 0.28, 0.06), stiffness_nm_per_rad=(0.0, 1.2, 0.0), neutral_rad=(0.0, 1.8, 0.0)
)


@pytest.fixture(scope="module")
def spring() -> tuple[sim.SimulatedSession, IdentificationData]:
    simulated = sim.simulate_cell(sim.human_arm_cell(seed=12, passive=SPRING, duration_s=60.0))
    return simulated, identification_data_from_session(simulated.session)


def test_without_the_fallback_the_model_it_names_takes_the_spring_up(
    spring: tuple[sim.SimulatedSession, IdentificationData],
) -> None:
    simulated, data = spring
    fixed = identify_joint(data)
    (elastic,) = [f for f in fixed.findings if f.code is FindingCode.ELASTIC_TERM]
    assert not fixed.valid and elastic.where == "elbow" and not elastic.values["fallback"]
    named = identify_joint(data, JointConfig(passive=PassiveModel.parse(elastic.values["passive_option"])))
    assert named.valid and FindingCode.ELASTIC_TERM not in [f.code for f in named.findings], named.message
    truth = simulated.truth.static_moments_kgm
    for k, segment in enumerate(("upper_arm", "forearm", "hand")):
        z = abs(named.value("static_moment_kgm", segment) - truth[k]) / named.std_of("static_moment_kgm", segment)
        assert z < 3.0, (segment, z)


def test_with_the_fallback_it_names_the_model_the_estimate_used(
    spring: tuple[sim.SimulatedSession, IdentificationData],
) -> None:
    _, data = spring
    fallen_back = identify_joint(data, JointConfig(elastic_fallback=True))
    (elastic,) = [f for f in fallen_back.findings if f.code is FindingCode.ELASTIC_TERM]
    assert fallen_back.valid and elastic.values["fallback"]
    named = identify_joint(data, JointConfig(passive=PassiveModel.parse(elastic.values["passive_option"])))
    np.testing.assert_allclose(named.values, fallen_back.values, rtol=1e-9, atol=1e-12)
