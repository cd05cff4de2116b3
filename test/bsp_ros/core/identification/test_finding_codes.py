"""Each finding of the stacked identification, made to happen on a simulated session with known parameters."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from bsp_ros.core import model
from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode, Severity, findings_of
from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint, judgement
from bsp_ros.core.identification.joint import refit as refit_module
from bsp_ros.core.identification.joint.refit import refit_held
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.pipeline import IdentifyOptions, fused, identify_session

# The simulated markers sit on the joint centres: no placement uncertainty to add.
EXACT = JointConfig(marker_placement_sd_m=0.0)


@pytest.fixture(scope="module")
def session() -> sim.SimulatedSession:
    """60 s of a 3-segment arm drawn from the anthropometric prior, paper-like noise."""
    subject = sim.SubjectTruth.from_anthropometry("male", 75.0, 1.78, 3, rng=np.random.default_rng(7))
    return sim.simulate_cell(sim.human_arm_cell(subject=subject, seed=7, duration_s=60.0))


@pytest.fixture(scope="module")
def data(session: sim.SimulatedSession) -> IdentificationData:
    return identification_data_from_session(session.session)


def _codes(result: IdentificationResult) -> list[tuple[FindingCode, str]]:
    return [(f.code, f.where) for f in result.findings]


def _without_hand(data: IdentificationData, session: sim.SimulatedSession, share: float) -> IdentificationData:
    """``data`` with ``share`` of the hand's gravity torques taken away (a lighter hand, or a negative one)."""
    beta_hand = session.truth.static_moments_kgm[2]
    return dataclasses.replace(
        data, tau_nm=data.tau_nm - share * model.gravity_regressor(data.q_rad)[:, :, 2] * beta_hand
    )


def test_a_clean_session_is_valid_without_a_weak_or_invalid_finding(data: IdentificationData) -> None:
    result = identify_joint(data, EXACT)
    assert result.valid and not result.weak, result.message
    assert all(f.severity is Severity.NOTE for f in result.findings)


def test_wrench_spikes_are_removed_and_counted(data: IdentificationData) -> None:
    tau = data.tau_nm.copy()
    tau[[500, 1500, 2500], 1] += 20.0
    result = identify_joint(dataclasses.replace(data, tau_nm=tau), EXACT)
    (spikes,) = [f for f in result.findings if f.code is FindingCode.WRENCH_SPIKES_REMOVED]
    assert result.valid and spikes.values["n"] == 3


def test_many_stretches_far_off_the_model_make_it_invalid(data: IdentificationData) -> None:
    tau = data.tau_nm.copy()
    for start in range(100, data.t_ns.size - 40, 200):  # 10 % of the samples, in stretches no spike filter takes
        tau[start : start + 20, 0] += 5.0
    result = identify_joint(dataclasses.replace(data, tau_nm=tau), EXACT)
    assert not result.valid and FindingCode.FAR_OFF_SAMPLES in [c for c, _ in _codes(result)]


def test_samples_whose_removal_moves_the_estimate_make_it_hang_on_them(data: IdentificationData) -> None:
    tau = data.tau_nm.copy()
    tau[3000:3060, 0] += 3.0  # 1 % of the samples
    # Judged as samples far off the fit, not as a stretch of muscle activity (which is what it would be taken for).
    config = dataclasses.replace(EXACT, check_activity=False)
    kept = identify_joint(dataclasses.replace(data, tau_nm=tau), config)
    assert kept.valid and FindingCode.FIT_OUTLIERS_REMOVED in [c for c, _ in _codes(kept)]
    # Judged with no shift allowed, their removal is what the estimate hangs on.
    strict = identify_joint(dataclasses.replace(data, tau_nm=tau), dataclasses.replace(config, max_outlier_shift=0.0))
    assert not strict.valid and FindingCode.HANGS_ON_FEW_SAMPLES in [c for c, _ in _codes(strict)]


def test_a_noisy_wrist_velocity_is_named_and_too_few_clear_directions_invalidate(data: IdentificationData) -> None:
    noise = data.velocity_noise_rad_s.copy()
    typical = np.percentile(np.abs(data.velocity_rad_s), 95, axis=0)
    noise[2] = 0.19 * typical[2]  # 4 sd of it is 0.75 of the typical speed: most wrist samples in the dead band
    result = identify_joint(dataclasses.replace(data, velocity_noise_rad_s=noise), EXACT)
    codes = _codes(result)
    assert (FindingCode.DIRECTION_NOISY, "wrist") in codes and (FindingCode.DIRECTION_UNCLEAR, "wrist") in codes
    assert not result.valid and result.weak is False


def test_a_joint_that_hardly_moves_leaves_too_few_usable_samples(data: IdentificationData) -> None:
    velocity = data.velocity_rad_s.copy()
    moving = np.zeros(data.t_ns.size, dtype=bool)
    moving[::3000] = True
    velocity[~moving, 2] = 0.0
    result = identify_joint(dataclasses.replace(data, velocity_rad_s=velocity), EXACT)
    assert not result.valid and result.findings[0].code is FindingCode.TOO_FEW_USABLE_SAMPLES


def test_a_static_moment_the_data_put_below_zero_is_invalid_and_one_at_zero_is_open(
    data: IdentificationData, session: sim.SimulatedSession
) -> None:
    negative = identify_joint(_without_hand(data, session, 1.05), EXACT)
    assert not negative.valid and (FindingCode.STATIC_MOMENT_AT_BOUND, "hand") in _codes(negative)
    zero = identify_joint(_without_hand(data, session, 1.0), EXACT)
    assert zero.valid and _codes(zero) == [(FindingCode.STATIC_MOMENT_OPEN, "hand")]


def test_a_light_hand_s_static_moment_is_uncertain(data: IdentificationData, session: sim.SimulatedSession) -> None:
    result = identify_joint(_without_hand(data, session, 0.9), JointConfig())
    assert result.valid and result.weak and (FindingCode.UNCERTAIN_STATIC_MOMENT, "hand") in _codes(result)


def test_friction_the_data_put_below_zero_sits_at_its_bound(data: IdentificationData) -> None:
    tau = data.tau_nm.copy()
    tau[:, 2] -= 2 * 0.06 * np.sign(data.velocity_rad_s[:, 2])  # the wrist's 0.06 Nm friction, reversed
    result = identify_joint(dataclasses.replace(data, tau_nm=tau), EXACT)
    assert (FindingCode.PARAMETER_AT_BOUND, "wrist") in _codes(result)


def test_the_condition_number_thresholds_name_poor_excitation(data: IdentificationData, monkeypatch) -> None:
    poorly = identify_joint(data, dataclasses.replace(EXACT, max_condition=1.0))
    assert poorly.valid and FindingCode.POORLY_EXCITED in [c for c, _ in _codes(poorly)]
    monkeypatch.setattr(judgement, "UNIDENTIFIABLE_CONDITION", 1.0)
    unidentified = identify_joint(data, EXACT)
    assert not unidentified.valid and FindingCode.NOT_IDENTIFIABLE in [c for c, _ in _codes(unidentified)]


def test_a_spring_the_fixed_model_lacks_is_taken_up_by_the_model_the_data_choose() -> None:
    passive = sim.PassiveTruth(
        coulomb_nm=(0.5, 0.28, 0.06), stiffness_nm_per_rad=(0.0, 1.2, 0.0), neutral_rad=(0.0, 1.8, 0.0)
    )
    spring = sim.simulate_cell(sim.human_arm_cell(seed=12, passive=passive, duration_s=60.0))
    result = identify_joint(identification_data_from_session(spring.session), JointConfig(elastic_fallback=True))
    codes = [c for c, _ in _codes(result)]
    assert result.valid and result.weak and FindingCode.ELASTIC_TERM in codes
    assert FindingCode.MODEL_CHOICE_SPREAD in codes


def test_a_refit_on_another_arm_is_refused(data: IdentificationData) -> None:
    held = identify_joint(data, EXACT).held
    assert held is not None
    paper = sim.simulate_cell(sim.paper_mechanical_arm_cell(seed=3, duration_s=60.0))
    result = refit_held(identification_data_from_session(paper.session), held, EXACT)
    assert not result.valid and result.findings[0].code is FindingCode.NOT_SAME_ARM


def test_a_fit_without_finite_values_is_invalid(data: IdentificationData, monkeypatch) -> None:
    held = identify_joint(data, EXACT).held
    assert held is not None
    solve = refit_module.fit_problem

    def broken(problem):  # a solver that returned NaN (a singular system the checks did not catch)
        fit = solve(problem)
        return dataclasses.replace(fit, values=np.full_like(fit.values, np.nan))

    monkeypatch.setattr(refit_module, "fit_problem", broken)
    result = refit_held(data, held, EXACT)
    assert not result.valid and FindingCode.NON_FINITE in [c for c, _ in _codes(result)]


def test_a_prior_that_cannot_be_fused_is_a_note_not_a_failure(data: IdentificationData, monkeypatch) -> None:
    result = identify_joint(data, EXACT)

    def singular(*args, **kwargs):
        raise np.linalg.LinAlgError("singular matrix")

    monkeypatch.setattr("bsp_ros.core.pipeline.fuse_static_moments", singular)
    posterior, noted = fused(result, data, SubjectInfo())
    assert posterior is None and noted.valid
    assert noted.findings[-1].code is FindingCode.FUSION_FAILED and "singular matrix" in noted.warnings[-1]


def test_the_prior_s_assumptions_are_notes_of_the_estimate(session: sim.SimulatedSession) -> None:
    document = identify_session(session.session, IdentifyOptions(marker_placement_sd_m=0.0))
    notes = [f.text for f in findings_of(document["quality"]) if f.code is FindingCode.PRIOR_NOTE]
    assert document["quality"]["valid"] and any("no body mass given" in text for text in notes), notes
