"""A held model refitted to newer samples: one fit, no model checks (a live window between its checks)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.activity import Activity
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.drift import drift_columns
from bsp_ros.core.identification.joint.emg_activity import EmgEvidence, emg_evidence, emg_values, with_emg
from bsp_ros.core.identification.joint.held import HeldModel
from bsp_ros.core.identification.joint.identify import failed_result
from bsp_ros.core.identification.joint.judgement import UNIDENTIFIABLE_CONDITION, unidentifiable_problem
from bsp_ros.core.identification.joint.outliers import far_off_problem, fit_outliers, too_far_off
from bsp_ros.core.identification.joint.placement_covariance import placement_covariance
from bsp_ros.core.identification.joint.relaxed import activity_finding, detect_activity
from bsp_ros.core.identification.joint.samples import Samples, usable_samples
from bsp_ros.core.identification.joint.steps import prior_share
from bsp_ros.core.identification.joint.torque_response import TorqueResponse
from bsp_ros.core.identification.ledger import Ledger, Term
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.identification.stacked import Fit, Problem, augmented, build_problem, fit_problem
from bsp_ros.core.methods import Method
from bsp_ros.core.streams import joints_for

# The findings of the arm's activity: with EMG, a refit's own stand for the held ones.
_ACTIVITY_CODES = frozenset({FindingCode.ARM_ACTIVE, FindingCode.TOO_LITTLE_RELAXED})


def refit_held(data: IdentificationData, held: HeldModel, config: JointConfig | None = None) -> IdentificationResult:
    """Refit the model ``held`` chose to ``data``: newer samples of the same arm and session.

    What the data alone decide is the data's: the rows with a trustworthy direction of motion, wrench spikes and
    samples far off the fit (removed), the parameters, their fit's own HAC covariance, the condition number and
    whether the motion still excites every joint, and the marker placement's share of the covariance. What the
    model checks decided is held: the passive model, the friction transition widths, a drift's model, the other
    systematic shares of the covariance (the model's choice, the friction shape, the drift's level) and what the
    checks found the model lacks, which also makes this result invalid. Costs one fit (two with a modelled drift,
    one more after removing far-off samples).

    Where ``data`` has EMG envelopes, the stretches they show active in these samples are left out, as the
    identification with its checks leaves them out (:func:`leave_out_activity`): with the torque's stretches where
    too many samples lie far off the fit (their union), alone otherwise. The refit's ``arm_active`` and
    ``emg_unusable`` findings then stand for the held ones of the same code: they describe these samples.

    Parameters
    ----------
    data : the newer samples; the same chain as the held identification's.
    held : :attr:`IdentificationResult.held` of an identification with its model checks.
    config : the thresholds and prior of that identification; its passive model is replaced by the held one.

    Returns
    -------
    IdentificationResult, with ``held`` passed on for the next refit.
    """
    config = dataclasses.replace(config or JointConfig(), passive=held.passive, check_elastic=False, check_drift=False)
    widths = held.widths_rad_s if held.widths_rad_s.any() else None
    samples = usable_samples(data, config, widths)
    problems, warnings = list(samples.problems), list(samples.warnings)
    if samples.problem.names != held.names:
        problems.append(Finding(code=FindingCode.NOT_SAME_ARM))
    if samples.too_few is not None and not problems:
        problems.append(samples.too_few)
    if problems:
        return failed_result(data, samples.problem.names, problems, warnings)
    samples, evidence, emg_alone = _left_out_by_emg(data, config, samples, widths)
    if evidence is not None:
        warnings += evidence.notes
    if emg_alone is not None and _too_little_left(emg_alone, samples):
        return failed_result(data, samples.problem.names, [emg_alone], warnings)
    kept = _without_far_off(data, config, samples, widths, evidence, emg_alone)
    problems += kept.problems
    warnings += kept.notes
    # With EMG the refit finds the stretches of these samples itself: its findings of them stand for the held ones.
    found = {f.code for f in (*kept.notes, *kept.problems) if f.code in _ACTIVITY_CODES}
    decided = set() if evidence is None else {FindingCode.EMG_UNUSABLE, *found}
    fit, ledger, own = _held_covariance(data, kept.problem, kept.fit, held)
    if fit.condition > UNIDENTIFIABLE_CONDITION:
        problems.append(unidentifiable_problem(fit.condition))
    problems += list(held.check_problems)
    if not problems and not np.isfinite(fit.values).all():
        problems.append(Finding(code=FindingCode.NON_FINITE))
    joints = joints_for(data.n_joints)
    removed = {"wrench_spikes": int(samples.spikes.sum()), "fit_outliers": kept.removed}
    diagnostics = {
        **held.diagnostics,
        "hac_lags": fit.lags,
        "passive_curves": {} if held.curves is None else held.curves.curves(fit),
        "rows_used": {j: int(c) for j, c in zip(joints, kept.problem.rows.sum(axis=0), strict=True)},
        "removed_samples": {k: v for k, v in removed.items() if v},
        "prior_share": prior_share(kept.problem, own),
    }
    return IdentificationResult(
        method=Method.JOINT,
        names=kept.problem.names,
        values=fit.values,
        covariance=fit.covariance,
        ledger=ledger,
        findings=(*problems, *warnings, *(w for w in held.warnings if w not in warnings and w.code not in decided)),
        summary=f"identified from {data.t_ns.size} samples",
        condition_number=fit.condition,
        residual_rms_nm={joint: float(np.sqrt(np.nanmean(fit.residual[:, j] ** 2))) for j, joint in enumerate(joints)},
        n_samples=int(data.t_ns.size),
        diagnostics=diagnostics,
        torque_response=TorqueResponse.of(kept.problem, fit),
        held=held,
    )


@dataclass(frozen=True, kw_only=True)
class _Kept:
    """The refit's problem and fit once samples far off it are removed, and what that found."""

    problem: Problem
    fit: Fit
    problems: tuple[Finding, ...]
    notes: tuple[Finding, ...]
    removed: int


def _left_out_by_emg(
    data: IdentificationData, config: JointConfig, samples: Samples, widths: np.ndarray | None
) -> tuple[Samples, EmgEvidence | None, Finding | None]:
    """``samples`` without the stretches the window's EMG shows active, what the EMG shows (None without EMG or the
    activity check), and the ``arm_active`` or ``too_little_relaxed`` finding of its stretches alone (None where it
    shows none)."""
    evidence = emg_evidence(data, config.emg) if config.check_activity else None
    if evidence is None or evidence.activity is None or not evidence.active.any():
        return samples, evidence, None
    rows = samples.rows & ~evidence.active[:, None]
    problem = build_problem(data, config.passive, rows, widths, samples.extras)
    torque = Activity(active=np.zeros(data.t_ns.size, dtype=bool), spans_s=(), peak_nm=np.zeros(data.n_joints))
    values = emg_values(torque.active, evidence.active, evidence.activity)
    finding = activity_finding(data, config, with_emg(torque, evidence, data.t_ns), values)
    return dataclasses.replace(samples, rows=rows, problem=problem), evidence, finding


def _too_little_left(finding: Finding, samples: Samples) -> bool:
    """Whether the stretches of ``finding`` leave too little to fit: too little of a relaxed arm, or a joint with
    fewer rows than parameters."""
    too_few = (samples.rows.sum(axis=0) < len(samples.problem.names)).any()
    return finding.code is FindingCode.TOO_LITTLE_RELAXED or bool(too_few)


def _without_far_off(
    data: IdentificationData,
    config: JointConfig,
    samples: Samples,
    widths: np.ndarray | None,
    evidence: EmgEvidence | None = None,
    emg_alone: Finding | None = None,
) -> _Kept:
    """The fit of ``samples``, refitted without the samples far off it (too many: the model does not fit);
    ``evidence``: what the window's EMG shows (its stretches already out of ``samples``), where it has EMG;
    ``emg_alone``: the finding of its stretches alone, the note where the torque's are not looked for."""
    fit = fit_problem(samples.problem)
    far = fit_outliers(fit, config)
    n_far = int(far.sum())
    if too_far_off(n_far, samples.usable):
        calmed = _without_activity(data, config, samples, widths, fit, evidence)
        if calmed is not None:
            return calmed
        far_off = far_off_problem(n_far, samples.usable, config)
        return _Kept(problem=samples.problem, fit=fit, problems=(far_off,), notes=(), removed=0)
    notes = () if emg_alone is None else (emg_alone,)
    if not n_far:
        return _Kept(problem=samples.problem, fit=fit, problems=(), notes=notes, removed=0)
    problem = build_problem(data, config.passive, samples.rows & ~far[:, None], widths, samples.extras)
    removed = Finding(code=FindingCode.FIT_OUTLIERS_REMOVED, values={"n": n_far, "outlier_sd": config.outlier_sd})
    return _Kept(problem=problem, fit=fit_problem(problem), problems=(), notes=(*notes, removed), removed=n_far)


def _without_activity(
    data: IdentificationData,
    config: JointConfig,
    samples: Samples,
    widths: np.ndarray | None,
    fit: Fit,
    evidence: EmgEvidence | None = None,
) -> _Kept | None:
    """Between a live window's checks, too many samples far off the held model's fit: stretches of muscle activity
    (:func:`detect_activity`) left out as the checks' identification leaves them; None where none explain it.
    ``evidence``: the window's EMG, whose stretches (out of ``samples`` already) join the torque's in the finding."""
    if not config.check_activity:
        return None
    activity = detect_activity(data, config, fit.residual)
    emg = None
    if evidence is not None and evidence.activity is not None:
        emg = emg_values(activity.active, evidence.active, evidence.activity)
        activity = with_emg(activity, evidence, data.t_ns)
    finding = activity_finding(data, config, activity, emg)
    if not activity.spans_s or finding.code is not FindingCode.ARM_ACTIVE:
        return None
    problem = build_problem(data, config.passive, samples.rows & ~activity.active[:, None], widths, samples.extras)
    refit = fit_problem(problem)
    if too_far_off(int(fit_outliers(refit, config).sum()), samples.usable):
        return None
    return _Kept(problem=problem, fit=refit, problems=(), notes=(finding,), removed=0)


def _held_covariance(
    data: IdentificationData, problem: Problem, fit: Fit, held: HeldModel
) -> tuple[Fit, Ledger, np.ndarray]:
    """The refit with its covariance: its own (HAC), the placement's share for these samples, and the held model's
    systematic terms; the ledger of those terms, and the fit's own covariance."""
    own = fit.covariance
    placement = None
    if held.placement_sd_m.any():
        placement = placement_covariance(data, problem, fit, held.placement_sd_m)
        if held.placement_factor is not None:
            # The check's reweighting share of the term (placement_reweighting.py), held as the noise's is.
            placement = placement * np.outer(held.placement_factor, held.placement_factor)
        # As the full identification, the noise term holds only what the offsets leave (joint/steps.py): its
        # ratio to the raw residual's, from the check, rescales this fit's (a refit costs one fit).
        own = own * np.outer(held.noise_scale, held.noise_scale)
    if held.drift:
        # The drift's rate is the newer data's; its unknown level's share is in the held systematic covariance.
        extra, names, _ = drift_columns(data)
        wide = fit_problem(augmented(problem, extra, names))
        p = len(problem.names)
        fit = dataclasses.replace(wide, values=wide.values[:p], design=wide.design[:p, :p])
        own = wide.covariance[:p, :p]
    ledger = Ledger.of(Term.SENSOR_NOISE, own)
    if placement is not None:
        ledger = ledger.plus(Term.MARKER_PLACEMENT, placement)
    ledger = ledger.joined(held.systematic)
    return dataclasses.replace(fit, covariance=ledger.total(own.shape[0])), ledger, own
