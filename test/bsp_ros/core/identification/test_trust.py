"""A VALID that means trustworthy: smooth friction transitions, elastic offsets and the stated assumption."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint import identify_joint
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.core.tare import estimate_tare

COULOMB_NM = np.array([0.5, 0.28, 0.06])


def data_with_transition(width_rad_s: float, seed: int = 0) -> tuple[IdentificationData, sim.SessionTruth]:
    """60 s of the human arm whose friction is ``c tanh(v / width)`` (added to the torques of a
    friction-free simulation, with the true joint velocities)."""
    spec = sim.human_arm_cell(seed=seed, duration_s=60.0, passive=sim.PassiveTruth(coulomb_nm=(0.0, 0.0, 0.0)))
    simulated = sim.simulate_cell(spec)
    data = identification_data_from_session(simulated.session)
    simulator = sim.CellSimulator(spec)
    velocity = simulator.joint_velocities_rad_s(simulator.seconds_since_start(data.t_ns))
    return dataclasses.replace(data, tau_nm=data.tau_nm + COULOMB_NM * np.tanh(velocity / width_rad_s)), simulated.truth


def _assert_within_3_std(result: IdentificationResult, truth: sim.SessionTruth) -> None:
    """Every Coulomb amplitude and static moment holds the truth within 3 of its std."""
    for j, joint in enumerate(("shoulder", "elbow", "wrist")):
        z = (result.value("coulomb_nm", joint) - COULOMB_NM[j]) / result.std_of("coulomb_nm", joint)
        assert abs(z) < 3, (joint, z)
    for segment, beta in zip(truth.segment_names, truth.static_moments_kgm, strict=True):
        assert abs(result.value("static_moment_kgm", segment) - beta) < 3 * result.std_of("static_moment_kgm", segment)


def test_a_narrow_friction_transition_is_modelled_and_the_coulomb_amplitudes_cover_the_truth() -> None:
    data, truth = data_with_transition(0.001)
    result = identify_joint(data)
    assert result.valid, result.message
    assert FindingCode.FRICTION_SMOOTH in [f.code for f in result.findings]
    _assert_within_3_std(result, truth)


def test_a_joint_that_never_leaves_the_transition_keeps_its_estimate_with_the_std_it_has() -> None:
    """At 2 mrad/s the wrist (peak 5.8 mrad/s) stays inside its transition: its Coulomb amplitude is weakly
    identified, not wrong; the estimate stays valid and every parameter holds the truth within 3 std."""
    data, truth = data_with_transition(0.002)
    result = identify_joint(data)
    assert result.valid, result.message
    assert any(f.code is FindingCode.FRICTION_TRANSITION_WEAK and f.where == "wrist" for f in result.findings)
    _assert_within_3_std(result, truth)


def test_a_sign_step_is_not_taken_for_a_transition() -> None:
    data, _ = data_with_transition(1e-9)  # tanh at 1 nrad/s is the sign step
    result = identify_joint(data)
    assert result.valid, result.message
    assert not any(result.diagnostics["friction_transition_rad_s"].values())


@pytest.fixture(scope="module")
def clean_document() -> dict:
    return identify_session(sim.simulate_cell(sim.human_arm_cell(seed=6, duration_s=60.0)).session)


def test_the_no_offset_assumption_is_stated_with_a_sensitivity_that_matches_a_real_offset(clean_document) -> None:
    (assumption,) = clean_document["quality"]["assumptions"]
    assert "no elastic passive offset" in assumption["assumption"]
    predicted = assumption["static_moment_shift_kgm_per_0_05_nm"]["wrist"]["hand"]
    spec = sim.human_arm_cell(seed=6, duration_s=60.0)
    offset = dataclasses.replace(spec.passive, offset_nm=(0.0, 0.0, 0.05))
    biased = identify_session(sim.simulate_cell(dataclasses.replace(spec, passive=offset)).session)
    shift = (
        biased["segments"]["hand"]["static_moment_kgm"]["value"]
        - clean_document["segments"]["hand"]["static_moment_kgm"]["value"]
    )
    assert shift == pytest.approx(predicted, rel=0.1)


@pytest.fixture(scope="module")
def elastic_session() -> tuple[sim.SimulatedSession, dict]:
    spec = sim.human_arm_cell(seed=7, duration_s=60.0)
    passive = dataclasses.replace(spec.passive, offset_nm=(0.2, 0.2, 0.2))
    simulated = sim.simulate_cell(dataclasses.replace(spec, passive=passive))
    return simulated, simulated.truth.to_dict()


def test_by_default_an_elastic_offset_lets_the_data_choose_the_elastic_terms_and_the_std_covers_the_truth(
    elastic_session,
) -> None:
    simulated, truth = elastic_session
    document = identify_session(simulated.session)
    quality = document["quality"]
    elastic = [f for f in findings_of(quality) if f.code is FindingCode.ELASTIC_TERM]
    assert elastic and all(f.values["fallback"] for f in elastic), quality["warnings"]
    assert document["diagnostics"]["passive_selection"], "the elastic terms were not chosen by the data"
    assert quality["valid"], quality["message"]
    for segment, q in document["segments"].items():
        value, std = q["static_moment_kgm"]["value"], q["static_moment_kgm"]["std"]
        assert abs(value - truth["segments"][segment]["static_moment_kgm"]) < 3 * std, segment
    for joint, q in document["joints"].items():
        assert abs(q["coulomb_nm"]["value"] - truth["joints"][joint]["coulomb_nm"]) < 3 * q["coulomb_nm"]["std"], joint


def test_an_elastic_offset_makes_a_model_the_user_fixed_invalid_with_its_cause_named(elastic_session) -> None:
    simulated, _ = elastic_session
    options = IdentifyOptions(passive=PassiveModel.parse("coulomb"), elastic_fallback=False)
    quality = identify_session(simulated.session, options)["quality"]
    assert not quality["valid"]
    assert FindingCode.ELASTIC_LACKING in [f.code for f in findings_of(quality)]
    assert FindingCode.ELASTIC_TERM in [f.code for f in findings_of(quality)]


def test_the_tare_uncertainty_joins_the_estimate_of_the_elastic_terms_the_data_chose() -> None:
    # The tare's sensitivity refits the model the estimate used (here chosen by the data), not the default one.
    spec = sim.human_arm_cell(seed=7, duration_s=60.0)
    stiff = dataclasses.replace(spec.passive, stiffness_nm_per_rad=(0.0, 1.2, 0.0), neutral_rad=(0.0, 1.87, 0.0))
    spec = dataclasses.replace(spec, passive=stiff)
    tare_spec = sim.TareSpec(duration_s=20.0, start_offset_s=-60.0, swing_rpy_deg=(20.0, 20.0, 0.0))
    recording = sim.simulate_tare(spec, tare_spec).wrench
    tare = estimate_tare(recording.t_ns, recording.force_n, recording.torque_nm, recording.frame_id)
    document = identify_session(sim.simulate_cell(spec).session, IdentifyOptions(tare=tare))
    assert document["diagnostics"]["passive_model"] != "coulomb"  # the data chose elastic terms
    added = document["quality"]["tare"]["std_added"]
    assert set(added) == set(document["diagnostics"]["parameters"])
    assert all(v > 0 for k, v in added.items() if k.startswith("static_moment_kgm/"))
