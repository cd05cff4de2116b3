"""Stretches of muscle activity, added to a simulated relaxed arm with known parameters, are found and left out."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.joint.activity import active_stretches
from bsp_ros.core.identification.joint.contact_slip import slip_lever_n
from bsp_ros.core.identification.joint.identify import _start
from bsp_ros.core.identification.ledger import Term
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.model import contact_lever_sums

# The simulated markers sit on the joint centres: no placement uncertainty to add.
EXACT = JointConfig(marker_placement_sd_m=0.0)


@pytest.fixture(scope="module")
def session() -> sim.SimulatedSession:
    """60 s of a 3-segment arm drawn from the anthropometric prior, paper-like noise."""
    subject = sim.SubjectTruth.from_anthropometry("male", 75.0, 1.78, 3, rng=np.random.default_rng(11))
    return sim.simulate_cell(sim.human_arm_cell(subject=subject, seed=11, duration_s=60.0))


@pytest.fixture(scope="module")
def data(session: sim.SimulatedSession) -> IdentificationData:
    return identification_data_from_session(session.session)


def bursts(data: IdentificationData, starts_s: list[float], share_of_gravity: float, seed: int) -> np.ndarray:
    """(N, n) joint torques of bursts of involuntary activity: each 1-3 s with a smooth rise and fall, its content
    at 0.3-2 Hz, each joint's peak ``share_of_gravity`` of that joint's RMS torque (Dewald and Beer 2001: 5-20 %)."""
    rng = np.random.default_rng(seed)
    t_s = (data.t_ns - data.t_ns[0]) * 1e-9
    rms = np.sqrt((data.tau_nm**2).mean(axis=0))
    out = np.zeros_like(data.tau_nm)
    for start in starts_s:
        length = rng.uniform(1.0, 3.0)
        inside = (t_s > start) & (t_s < start + length)
        envelope = np.where(inside, np.sin(np.pi * (t_s - start) / length) ** 2, 0.0)
        wobble = 1.0 + 0.5 * np.sin(2 * np.pi * rng.uniform(0.3, 2.0) * t_s)
        out += envelope[:, None] * wobble[:, None] * rng.choice([-1.0, 1.0], data.n_joints) * share_of_gravity * rms
    return out


def test_a_relaxed_session_has_no_active_stretch(data: IdentificationData) -> None:
    fit = _start(data, EXACT).fit
    activity = active_stretches(data.t_ns, data.q_rad, data.velocity_rad_s, fit.residual, np.full(3, 1e-3))
    assert activity.spans_s == () and not activity.active.any()


def test_bursts_are_found_where_they_are(data: IdentificationData) -> None:
    torque = bursts(data, [8.0, 23.0, 41.0], 0.10, seed=1)
    active = dataclasses.replace(data, tau_nm=data.tau_nm + torque)
    fit = _start(active, EXACT).fit
    found = active_stretches(data.t_ns, data.q_rad, data.velocity_rad_s, fit.residual, np.full(3, 1e-3))
    truth = np.abs(torque).max(axis=1) > 0.02 * np.abs(torque).max()
    assert len(found.spans_s) == 3
    assert (found.active & truth).sum() >= 0.95 * truth.sum()
    assert (found.active & ~truth).sum() <= 0.03 * (~truth).sum()


def test_an_arm_with_a_few_bursts_stays_valid_and_right(
    data: IdentificationData, session: sim.SimulatedSession
) -> None:
    truth = np.asarray(session.truth.static_moments_kgm)
    plain = identify_joint(data, EXACT)
    active = dataclasses.replace(data, tau_nm=data.tau_nm + bursts(data, [5.0, 19.0, 33.0, 47.0], 0.20, seed=2))
    without = identify_joint(active, dataclasses.replace(EXACT, check_activity=False))
    result = identify_joint(active, EXACT)
    assert not without.valid  # what the estimate was before the relaxed-arm check: thrown away
    assert result.valid and FindingCode.ARM_ACTIVE not in [f.code for f in plain.findings]
    (note,) = [f for f in result.findings if f.code is FindingCode.ARM_ACTIVE]
    assert note.values["n_stretches"] == 4 and 5.0 < note.values["active_s"] < 16.0
    _, beta, covariance = result.block("static_moment_kgm")
    z = (beta - truth) / np.sqrt(np.diag(covariance))
    assert np.abs(z).max() < 2.5, z


def test_an_arm_active_for_more_than_allowed_is_invalid_for_that_reason(data: IdentificationData) -> None:
    active = dataclasses.replace(data, tau_nm=data.tau_nm + bursts(data, list(np.arange(1.0, 58.0, 5.0)), 0.10, 3))
    assert identify_joint(active, EXACT).valid  # about 40 % active, the rest relaxed
    strict = dataclasses.replace(EXACT, activity=dataclasses.replace(EXACT.activity, max_active_share=0.3))
    result = identify_joint(active, strict)
    assert not result.valid and result.findings[0].code is FindingCode.TOO_LITTLE_RELAXED
    assert 50.0 < result.findings[0].values["relaxed_percent"] < 70.0


def test_torque_that_recurs_with_the_state_is_not_activity(data: IdentificationData) -> None:
    # An elastic moment the Coulomb model lacks recurs wherever the elbow is at that angle: the model's shortfall
    # (the elastic check's to judge), not the patient's activity.
    q = data.q_rad[:, 1]
    elastic = np.zeros_like(data.tau_nm)
    elastic[:, 1] = 2.0 * np.clip(q - np.percentile(q, 80), 0.0, None)
    shaped = dataclasses.replace(data, tau_nm=data.tau_nm + elastic)
    fit = _start(shaped, EXACT).fit
    found = active_stretches(data.t_ns, data.q_rad, data.velocity_rad_s, fit.residual, np.full(3, 1e-3))
    assert found.share < 0.02


def test_resistance_growing_with_speed_in_one_direction_is_named_as_possible_spasticity(
    data: IdentificationData,
) -> None:
    # A stretch reflex at the elbow (Lance 1980): above 0.6 of the typical speed, motion in one direction meets a
    # resistance growing with its speed (at most 0.085 Nm here, as in the MuJoCo patient cell's faster session);
    # the other direction and the slower motion meet none. The measured torque carries a resistance with the
    # motion's sign.
    velocity = data.velocity_rad_s[:, 1]
    threshold = 0.6 * np.percentile(np.abs(velocity), 90)
    reflex = np.zeros_like(data.tau_nm)
    reflex[:, 1] = -20.0 * np.clip(-velocity - threshold, 0.0, None)
    spastic = identify_joint(dataclasses.replace(data, tau_nm=data.tau_nm + reflex), EXACT)
    codes = [(f.code, f.where) for f in spastic.findings]
    assert (FindingCode.SPASTICITY, "elbow") in codes
    relaxed = identify_joint(data, EXACT)
    assert FindingCode.SPASTICITY not in [f.code for f in relaxed.findings]


def test_a_hand_that_slips_in_the_handle_is_followed_and_named(
    data: IdentificationData, session: sim.SimulatedSession
) -> None:
    # The contact point moves 8 mm along the hand in three slips of half a second (a hand sliding in its strap):
    # every joint's torque changes by the travel times the force's lever about the hand's direction.
    t_s = (data.t_ns - data.t_ns[0]) * 1e-9
    travel_m = 0.008 / 3 * sum(np.clip((t_s - start) / 0.5, 0.0, 1.0) for start in (12.0, 31.0, 47.0))
    lever = slip_lever_n(data.q_rad, data.lengths_m, data.tau_nm)
    slipped = dataclasses.replace(data, tau_nm=data.tau_nm + (travel_m * lever)[:, None])
    result = identify_joint(slipped, EXACT)
    assert result.valid
    (found,) = [f for f in result.findings if f.code is FindingCode.HAND_SLIPPED]
    assert 6.0 < found.values["slip_mm"] < 10.0
    _, beta, covariance = result.block("static_moment_kgm")
    z = (beta - np.asarray(session.truth.static_moments_kgm)) / np.sqrt(np.diag(covariance))
    assert np.abs(z).max() < 2.5, z
    assert FindingCode.HAND_SLIPPED not in [f.code for f in identify_joint(data, EXACT).findings]
    # With the passive model the data choose (other parameters than the fixed model's), the slip's covariance term
    # is that model's.
    chosen = identify_joint(slipped, dataclasses.replace(EXACT, passive=PassiveModel.parse("auto")))
    assert FindingCode.HAND_SLIPPED in [f.code for f in chosen.findings]
    slip_term = chosen.ledger.get(Term.CONTACT_SLIP)
    assert slip_term is not None and slip_term.shape == chosen.covariance.shape


def test_a_drifting_force_sensor_is_not_taken_for_a_slipping_hand(data: IdentificationData) -> None:
    # A vertical force offset creeping up by 0.6 N moves each joint's torque by its own lever (the shoulder's
    # several times the wrist's); a slip moves them alike.
    _, dz = contact_lever_sums(data.q_rad, data.lengths_m)
    creep_n = 0.01 * (data.t_ns - data.t_ns[0]) * 1e-9
    drifted = dataclasses.replace(data, tau_nm=data.tau_nm - dz * creep_n[:, None])
    assert FindingCode.HAND_SLIPPED not in [f.code for f in identify_joint(drifted, EXACT).findings]


def test_a_smooth_shortfall_with_no_sample_far_off_is_left_to_the_checks(data: IdentificationData) -> None:
    # A smooth 8 s bump at the elbow, as a musculoskeletal arm's passive muscles leave a wrong passive model on a
    # trajectory that never comes back: no sample stands far off the fit, so nothing calls for leaving it out (it
    # would hide the shortfall from the checks that judge the model).
    t_s = (data.t_ns - data.t_ns[0]) * 1e-9
    bump = np.zeros_like(data.tau_nm)
    inside = (t_s > 25.0) & (t_s < 33.0)
    bump[inside, 1] = 0.15 * np.sin(np.pi * (t_s[inside] - 25.0) / 8.0)
    result = identify_joint(dataclasses.replace(data, tau_nm=data.tau_nm + bump), EXACT)
    assert FindingCode.ARM_ACTIVE not in [f.code for f in result.findings]


def test_a_live_refit_between_checks_leaves_bursts_out_as_the_checks_do(
    data: IdentificationData, session: sim.SimulatedSession
) -> None:
    # A live window refits the model its last check held; bursts arriving in between are left out there too,
    # instead of the window turning invalid ("the model does not fit") until the next check.
    from bsp_ros.core.identification.joint.refit import refit_held

    held = identify_joint(data, EXACT).held
    assert held is not None
    active = dataclasses.replace(data, tau_nm=data.tau_nm + bursts(data, [5.0, 19.0, 33.0, 47.0], 0.20, seed=2))
    result = refit_held(active, held, EXACT)
    assert result.valid and FindingCode.ARM_ACTIVE in [f.code for f in result.findings]
    _, beta, covariance = result.block("static_moment_kgm")
    z = (beta - np.asarray(session.truth.static_moments_kgm)) / np.sqrt(np.diag(covariance))
    assert np.abs(z).max() < 2.5, z
    plain = refit_held(active, held, dataclasses.replace(EXACT, check_activity=False))
    assert not plain.valid and FindingCode.FAR_OFF_SAMPLES in [f.code for f in plain.findings]
