"""A held model refitted to newer samples: one fit, no model checks (a live window between its checks)."""

from __future__ import annotations

import dataclasses

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.drift import drift_columns
from bsp_ros.core.identification.joint.held import HeldModel
from bsp_ros.core.identification.joint.identify import failed_result
from bsp_ros.core.identification.joint.judgement import UNIDENTIFIABLE_CONDITION, unidentifiable_problem
from bsp_ros.core.identification.joint.outliers import far_off_problem, fit_outliers, too_far_off
from bsp_ros.core.identification.joint.placement_covariance import placement_covariance
from bsp_ros.core.identification.joint.samples import usable_samples
from bsp_ros.core.identification.joint.steps import prior_share
from bsp_ros.core.identification.joint.torque_response import TorqueResponse
from bsp_ros.core.identification.ledger import Ledger, Term
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.identification.stacked import augmented, build_problem, fit_problem
from bsp_ros.core.streams import joints_for


def refit_held(data: IdentificationData, held: HeldModel, config: JointConfig | None = None) -> IdentificationResult:
    """Refit the model ``held`` chose to ``data``: newer samples of the same arm and session.

    What the data alone decide is the data's: the rows with a trustworthy direction of motion, wrench spikes and
    samples far off the fit (removed), the parameters, their fit's own HAC covariance, the condition number and
    whether the motion still excites every joint, and the marker placement's share of the covariance. What the
    model checks decided is held: the passive model, the friction transition widths, a drift's model, the other
    systematic shares of the covariance (the model's choice, the friction shape, the drift's level) and what the
    checks found the model lacks, which also makes this result invalid. Costs one fit (two with a modelled drift,
    one more after removing far-off samples).

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
    n = data.n_joints
    joints = joints_for(n)
    widths = held.widths_rad_s if held.widths_rad_s.any() else None
    samples = usable_samples(data, config, widths)
    rows, spikes, problem, usable = samples.rows, samples.spikes, samples.problem, samples.usable
    problems, warnings = list(samples.problems), list(samples.warnings)
    if problem.names != held.names:
        problems.append(Finding(code=FindingCode.NOT_SAME_ARM))
    if samples.too_few is not None and not problems:
        problems.append(samples.too_few)
    if problems:
        return failed_result(data, problem.names, problems, warnings)
    fit = fit_problem(problem)
    far = fit_outliers(fit, config)
    n_far = int(far.sum())
    if too_far_off(n_far, usable):
        problems.append(far_off_problem(n_far, usable, config))
    elif n_far:
        problem = build_problem(data, config.passive, rows & ~far[:, None], widths, samples.extras)
        fit = fit_problem(problem)
        values = {"n": n_far, "outlier_sd": config.outlier_sd}
        warnings.append(Finding(code=FindingCode.FIT_OUTLIERS_REMOVED, values=values))
    own = fit.covariance
    placement = None
    if held.placement_sd_m.any():
        placement = placement_covariance(data, problem, fit, held.placement_sd_m)
    if held.drift:
        # The drift's rate is the newer data's; its unknown level's share is in the held systematic covariance.
        extra, names, _ = drift_columns(data)
        wide = fit_problem(augmented(problem, extra, names))
        p = len(problem.names)
        fit = dataclasses.replace(wide, values=wide.values[:p], design=wide.design[:p, :p])
        own = wide.covariance[:p, :p]
    shares = prior_share(problem, own)
    ledger = Ledger.of(Term.SENSOR_NOISE, own)
    if placement is not None:
        ledger = ledger.plus(Term.MARKER_PLACEMENT, placement)
    ledger = ledger.joined(held.systematic)
    fit = dataclasses.replace(fit, covariance=ledger.total(own.shape[0]))
    if fit.condition > UNIDENTIFIABLE_CONDITION:
        problems.append(unidentifiable_problem(fit.condition))
    problems += list(held.check_problems)
    if not problems and not np.isfinite(fit.values).all():
        problems.append(Finding(code=FindingCode.NON_FINITE))
    used = problem.rows.sum(axis=0)
    removed = {"wrench_spikes": int(spikes.sum()), "fit_outliers": 0 if too_far_off(n_far, usable) else n_far}
    diagnostics = {
        **held.diagnostics,
        "hac_lags": fit.lags,
        "passive_curves": {} if held.curves is None else held.curves.curves(fit),
        "rows_used": {j: int(c) for j, c in zip(joints, used, strict=True)},
        "removed_samples": {k: v for k, v in removed.items() if v},
        "prior_share": shares,
    }
    return IdentificationResult(
        method="joint",
        names=problem.names,
        values=fit.values,
        covariance=fit.covariance,
        ledger=ledger,
        findings=(*problems, *warnings, *(w for w in held.warnings if w not in warnings)),
        summary=f"identified from {data.t_ns.size} samples",
        condition_number=fit.condition,
        residual_rms_nm={joint: float(np.sqrt(np.nanmean(fit.residual[:, j] ** 2))) for j, joint in enumerate(joints)},
        n_samples=int(data.t_ns.size),
        diagnostics=diagnostics,
        torque_response=TorqueResponse.of(problem, fit),
        held=held,
    )
