"""The stacked identification of all joints: its steps in order, and the result they give."""

from __future__ import annotations

import dataclasses

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.checks import (
    check_elastic,
    check_perpendicular,
    check_placement,
    check_spasticity,
    check_stribeck,
)
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.grip import direction_share, keep_out_sticks
from bsp_ros.core.identification.joint.held import HeldModel
from bsp_ros.core.identification.joint.judgement import (
    UNIDENTIFIABLE_CONDITION,
    judge_fit,
    judge_parameters,
    unidentifiable_problem,
)
from bsp_ros.core.identification.joint.passive_offset import passive_offset_sensitivity
from bsp_ros.core.identification.joint.placement_covariance import covariance_from_products
from bsp_ros.core.identification.joint.relaxed import add_contact_slip, follow_the_hand, leave_out_activity
from bsp_ros.core.identification.joint.samples import usable_samples
from bsp_ros.core.identification.joint.speed_split import split_speeds
from bsp_ros.core.identification.joint.stage import Outcome, Stage, Step
from bsp_ros.core.identification.joint.steps import (
    add_friction_shape,
    add_marker_placement,
    add_model_choice,
    choose_passive_model,
    fit_friction_transitions,
    model_drift,
    prior_share,
    remove_far_off_samples,
)
from bsp_ros.core.identification.joint.torque_response import TorqueResponse
from bsp_ros.core.identification.joint.tremor_step import calm_tremor, widen_dithered_friction
from bsp_ros.core.identification.ledger import Ledger, Term
from bsp_ros.core.identification.result import IdentificationResult, ParameterName
from bsp_ros.core.identification.stacked import fit_problem
from bsp_ros.core.methods import Method
from bsp_ros.core.streams import joints_for

__all__ = [
    "STEPS",
    "UNIDENTIFIABLE_CONDITION",
    "failed_result",
    "identify_joint",
    "prior_share",
    "unidentifiable_problem",
]


def _direction_rows(stage: Stage) -> Stage:
    """With a Coulomb term, a joint whose direction of motion is trustworthy in too few samples cannot be judged."""
    if "coulomb" not in stage.config.passive.terms:
        return stage
    problems = []
    for j, joint in enumerate(joints_for(stage.n)):
        stuck = None if stage.stuck is None else stage.stuck[:, j]
        share = direction_share(stage.samples.rows[:, j], stage.samples.usable, stuck)
        if share < stage.config.min_row_share:
            values = {"share_percent": float(100 * share)}
            problems.append(Finding(code=FindingCode.DIRECTION_UNCLEAR, where=joint, values=values))
    return stage.apply(Outcome(problems=tuple(problems)))


# The identification, step by step: fits and the covariance terms they leave open, the verdict on the fit, then
# the model checks (what the model lacks; a live window runs them on some updates only).
STEPS: tuple[Step, ...] = (
    keep_out_sticks,
    _direction_rows,
    follow_the_hand,
    leave_out_activity,
    fit_friction_transitions,
    split_speeds,
    choose_passive_model,
    add_contact_slip,
    remove_far_off_samples,
    add_friction_shape,
    widen_dithered_friction,
    add_marker_placement,
    add_model_choice,
    model_drift,
    judge_fit,
    judge_parameters,
    check_stribeck,
    check_elastic,
    check_placement,
    check_spasticity,
    check_perpendicular,
)


def failed_result(
    data: IdentificationData, names: list[ParameterName], problems: list[Finding], warnings: list[Finding]
) -> IdentificationResult:
    """An invalid result: NaN values and covariance, with ``problems`` (invalid findings) and ``warnings``."""
    p = len(names)
    return IdentificationResult(
        method=Method.JOINT,
        names=names,
        values=np.full(p, np.nan),
        covariance=np.full((p, p), np.nan),
        findings=(*problems, *warnings),
        n_samples=int(data.t_ns.size),
    )


def _start(data: IdentificationData, config: JointConfig) -> Stage | IdentificationResult:
    """The usable samples (tremor taken out of their torques) and the first fit, or the result where too few
    samples are usable."""
    data, tremor = calm_tremor(data, config)
    samples = usable_samples(data, config)
    samples = dataclasses.replace(samples, warnings=[*tremor, *samples.warnings])
    if samples.too_few is not None:
        return failed_result(data, samples.problem.names, samples.problems or [samples.too_few], samples.warnings)
    fit = fit_problem(samples.problem)
    n = data.n_joints
    return Stage(
        data=data,
        config=config,
        # How far each chain point may sit from where the data put it (skin markers; the robot's contact point).
        placement_sd_m=config.placement_sd_m(n, data.contact_from_robot),
        samples=samples,
        problem=samples.problem,
        fit=fit,
        ledger=Ledger.of(Term.SENSOR_NOISE, fit.covariance),
        widths_rad_s=np.zeros(n),
        spread_nm=np.zeros(n),
        notes=tuple(samples.warnings),
        data_notes=len(samples.warnings),
        data_problems=tuple(samples.problems),
    )


def identify_joint(data: IdentificationData, config: JointConfig | None = None) -> IdentificationResult:
    """Identify static moments and passive moments of all joints in one stacked problem (:data:`STEPS`).

    Wrench spikes are removed before the fit and samples far off the fit after it (counted in the
    warnings); if removing the latter moves a parameter by more than its standard deviation, the
    estimate is not valid: it would hang on a few samples. Nor is it valid when the residuals are far
    above the sensor noise the data shows (the model does not fit), when a static moment sits at its
    bound 0, or when most samples of a joint lie in the direction dead band.

    Parameters
    ----------
    data : samples with joint angles, direction velocities and measured torques.
    config : passive model and validity thresholds.

    Returns
    -------
    IdentificationResult with a HAC covariance and its ledger of named terms; ``valid`` False with its findings
    when the data cannot support the estimate.
    """
    stage = _start(data, config or JointConfig())
    for step in STEPS:
        if isinstance(stage, IdentificationResult):
            break
        stage = step(stage)
    if isinstance(stage, IdentificationResult):
        return stage
    return result_of(stage)


def _diagnostics(stage: Stage) -> dict[str, object]:
    """The figures behind the verdict, for the estimate's ``diagnostics``."""
    joints = joints_for(stage.n)
    noise = stage.noise_nm if stage.noise_nm is not None else np.full(stage.n, np.nan)
    misfit = stage.misfit if stage.misfit is not None else np.full(stage.n, np.nan)
    removed = {"wrench_spikes": int(stage.samples.spikes.sum()), "fit_outliers": stage.removed}
    diagnostics: dict[str, object] = {
        "hac_lags": stage.fit.lags,
        "max_corr_with_gravity": stage.max_corr_with_gravity,
        "passive_model": stage.config.passive.label,
        "passive_selection": {} if stage.selection is None else stage.selection.to_dict(),
        "passive_curves": stage.passive_curves,
        "elastic_reference": {} if stage.elastic_reference is None else stage.elastic_reference.to_dict(),
        "rows_used": {j: int(c) for j, c in zip(joints, stage.problem.rows.sum(axis=0), strict=True)},
        "sensor_noise_nm": {j: float(v) for j, v in zip(joints, noise, strict=True)},
        "misfit_ratio": {j: float(v) for j, v in zip(joints, misfit, strict=True)},
        "removed_samples": {k: v for k, v in removed.items() if v},
        "offset_sensitivity_kgm_per_0_05_nm": passive_offset_sensitivity(stage.problem, stage.fit, stage.n),
        "friction_transition_rad_s": {j: float(v) for j, v in zip(joints, stage.widths_rad_s, strict=True)},
        "coulomb_transition_spread_nm": {j: float(v) for j, v in zip(joints, stage.spread_nm, strict=True)},
        "prior_share": stage.prior_share,
    }
    if stage.placement_check is not None:
        diagnostics["marker_placement"] = stage.placement_check.to_dict(stage.placement_sd_m)
    return diagnostics


def _held(stage: Stage, diagnostics: dict[str, object]) -> HeldModel:
    """What the steps chose, for refits of newer samples of the same arm between a live window's checks."""
    check = stage.placement_check
    factor = None
    placement, placement_fit = stage.placement, stage.placement_fit
    used = stage.ledger.get(Term.MARKER_PLACEMENT)
    if placement is not None and placement_fit is not None and used is not None:
        columns = check.column_factor if check is not None and check.scale > 1.0 else 1.0
        linear = np.diag(covariance_from_products(placement_fit, placement.products * columns))
        factor = np.sqrt(np.divide(np.diag(used), linear, out=np.ones_like(linear), where=linear > 0))
    return HeldModel(
        names=stage.problem.names,
        passive=dataclasses.replace(stage.config.passive, select=False),
        widths_rad_s=stage.widths_rad_s,
        drift=stage.drift is not None,
        placement_sd_m=stage.placement_sd_m if check is None else check.sd_m,
        systematic=stage.ledger.without(Term.SENSOR_NOISE, Term.MARKER_PLACEMENT),
        noise_scale=np.ones(len(stage.problem.names)) if stage.noise_scale is None else stage.noise_scale,
        curves=stage.curves,
        data_problems=stage.data_problems,
        check_problems=stage.check_problems,
        warnings=tuple(w for w in stage.notes[stage.data_notes :] if w not in stage.sample_notes),
        diagnostics=diagnostics,
        placement_factor=factor,
    )


def result_of(stage: Stage) -> IdentificationResult:
    """The identification result of the last stage."""
    fit = stage.fit
    if not stage.problems and not np.isfinite(fit.values).all():
        stage = stage.apply(Outcome(problems=(Finding(code=FindingCode.NON_FINITE),)))
    diagnostics = _diagnostics(stage)
    residual_rms = {
        joint: float(np.sqrt(np.nanmean(fit.residual[:, j] ** 2))) for j, joint in enumerate(joints_for(stage.n))
    }
    return IdentificationResult(
        method=Method.JOINT,
        names=stage.problem.names,
        values=fit.values,
        covariance=fit.covariance,
        ledger=stage.ledger,
        findings=(*stage.problems, *stage.notes),
        summary=f"identified from {stage.data.t_ns.size} samples",
        condition_number=fit.condition,
        residual_rms_nm=residual_rms,
        n_samples=int(stage.data.t_ns.size),
        diagnostics=diagnostics,
        torque_response=TorqueResponse.of(stage.problem, fit),
        held=_held(stage, diagnostics),
    )
