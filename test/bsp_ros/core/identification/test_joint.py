"""The stacked identification against simulated sessions with known parameters."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.passive import PassiveModel

# The simulated markers sit on the joint centres: no placement uncertainty to add.
EXACT = JointConfig(marker_placement_sd_m=0.0)


def _truth(session: sim.SimulatedSession, key: str, owner: str) -> float:
    truth = session.truth.to_dict()
    return float(truth["segments" if owner in truth["segments"] else "joints"][owner][key])


def _data_decided(result):
    """(index, key, owner) of the parameters the data decided (no prior, or the prior hardly counted)."""
    shares = result.diagnostics.get("prior_share", {})
    return [
        (i, key, owner)
        for i, (key, owner) in enumerate(result.names)
        if shares.get(f"{key}/{owner}", 0.0) < 0.05 and key != "perpendicular_moment_kgm"
    ]


def test_noise_free_session_recovers_every_parameter_to_001_percent(human_session_noise_free, without_noise) -> None:
    # The paper's quasi-static model on a quasi-static arm: exact up to the filters.
    quasi_static = sim.simulate_cell(without_noise(sim.human_arm_cell(seed=1, inertia=False)))
    data = identification_data_from_session(quasi_static.session)
    result = identify_joint(data, dataclasses.replace(EXACT, dynamics=False))
    assert result.valid, result.message
    for i, key, owner in _data_decided(result):
        truth = _truth(human_session_noise_free, key, owner)
        assert result.values[i] == pytest.approx(truth, rel=1e-4), (key, owner)
    np.testing.assert_allclose(data.lengths_m, human_session_noise_free.truth.lengths_m, rtol=1e-4)


def test_arm_with_inertia_holds_the_truth_within_its_std(human_session) -> None:
    """Real dynamics on the paper's slow protocol: the inertial terms enter the model with their prior, and
    what their uncertainty leaves uncertain is in the std, never taken as zero."""
    data = identification_data_from_session(human_session.session)
    result = identify_joint(data, EXACT)
    assert result.valid, result.message
    for i, (key, owner) in enumerate(result.names):
        truth = _truth(human_session, key, owner)
        assert abs(result.values[i] - truth) < 3 * result.std[i], (key, owner, result.values[i], truth)
        if key == "static_moment_kgm":
            assert result.values[i] == pytest.approx(truth, rel=0.005), (key, owner)


def test_paper_like_noise_meets_the_accuracy_targets(human_session) -> None:
    data = identification_data_from_session(human_session.session)
    result = identify_joint(data, EXACT)
    assert result.valid, result.message
    for i, key, owner in _data_decided(result):
        truth, value = _truth(human_session, key, owner), result.values[i]
        tolerance = 0.005 if key == "static_moment_kgm" else 0.10
        assert abs(value - truth) <= tolerance * truth, (key, owner, value, truth)
    np.testing.assert_allclose(data.lengths_m, human_session.truth.lengths_m, atol=1e-3)


def test_paper_like_noise_truth_lies_within_three_std(human_session) -> None:
    result = identify_joint(identification_data_from_session(human_session.session), EXACT)
    z = [(result.values[i] - _truth(human_session, k, o)) / result.std[i] for i, k, o in _data_decided(result)]
    assert np.all(np.abs(z) < 3.0), z
    # The perpendicular moments (truth 0) and the inertias (prior-dominated here) hold the truth too.
    for key in ("perpendicular_moment_kgm", "grouped_inertia_kgm2"):
        owners, values, covariance = result.block(key)
        for owner, value, var in zip(owners, values, np.diag(covariance), strict=True):
            assert abs(value - _truth(human_session, key, owner)) < 3 * np.sqrt(var), (key, owner)


def test_viscous_term_is_recovered_when_present_and_modelled() -> None:
    spec = sim.human_arm_cell(
        seed=11, passive=sim.PassiveTruth(coulomb_nm=(0.5, 0.28, 0.06), viscous_nms=(2.0, 1.5, 0.3))
    )
    session = sim.simulate_cell(spec)
    result = identify_joint(
        identification_data_from_session(session.session), JointConfig(passive=PassiveModel(("coulomb", "viscous")))
    )
    assert result.valid, result.message
    assert result.value("viscous_nms", "shoulder") == pytest.approx(2.0, rel=0.15)
    assert result.value("static_moment_kgm", "forearm") == pytest.approx(session.truth.static_moments_kgm[1], rel=0.005)


def test_unmodelled_elbow_stiffness_is_flagged_as_confounded_with_gravity() -> None:
    passive = sim.PassiveTruth(
        coulomb_nm=(0.5, 0.28, 0.06),
        stiffness_nm_per_rad=(0.0, 1.0, 0.0),
        neutral_rad=(0.0, np.radians(107.0), 0.0),
    )
    session = sim.simulate_cell(sim.human_arm_cell(seed=5, passive=passive))
    result = identify_joint(identification_data_from_session(session.session))
    elastic = [f for f in result.findings if f.code is FindingCode.ELASTIC_TERM]
    assert [f.where for f in elastic] == ["elbow"], result.warnings
    assert not result.valid and FindingCode.ELASTIC_LACKING in [f.code for f in result.findings]


def test_no_elastic_warning_without_stiffness_in_the_truth(human_session) -> None:
    result = identify_joint(identification_data_from_session(human_session.session))
    assert FindingCode.ELASTIC_TERM not in [f.code for f in result.findings], result.warnings


def test_zero_motion_is_invalid_with_a_message() -> None:
    still = sim.TrajectorySpec(
        center_deg=(-43.3, 29.5, 0.2),
        amplitude_deg=(0.0, 0.0, 0.0),
        period_s=(20.0, 20.0, 20.0),
        phase_rad=(0.0, 0.0, 0.0),
    )
    session = sim.simulate_cell(sim.human_arm_cell(seed=2, trajectory=still, duration_s=30.0))
    result = identify_joint(identification_data_from_session(session.session))
    assert not result.valid
    assert any(f.code is FindingCode.NO_MOTION and f.where == "shoulder" for f in result.findings), result.message


def test_too_few_samples_is_invalid_with_a_message(human_session) -> None:
    data = identification_data_from_session(human_session.session)
    result = identify_joint(data.window(0, 50))
    assert not result.valid
    assert FindingCode.TOO_FEW_SAMPLES in [f.code for f in result.findings], result.message


def test_nan_wrench_samples_are_removed_and_reported(human_session) -> None:
    wrench = human_session.session.wrench
    force = wrench.force_n.copy()
    force[100:120, 2] = np.nan
    force[200, 0] = np.inf
    session = dataclasses.replace(human_session.session, wrench=dataclasses.replace(wrench, force_n=force))
    data = identification_data_from_session(session)
    assert any("21 samples with NaN/Inf removed" in w for w in data.warnings)
    assert np.isfinite(data.tau_nm).all()
    assert identify_joint(data).valid
