"""The step that keeps the relaxed part of a session: stretches of muscle activity are found and left out."""

from __future__ import annotations

import dataclasses

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.joint.activity import Activity, active_stretches
from bsp_ros.core.identification.joint.outliers import MIN_OUTLIER_NM
from bsp_ros.core.identification.joint.stage import Outcome, Stage
from bsp_ros.core.identification.stacked import build_problem, fit_problem
from bsp_ros.core.streams import joints_for

__all__ = ["ACTIVITY_FLOOR_SHARE", "leave_out_activity"]

# Activity below this share of a joint's RMS torque is not looked for: it moves no estimate beyond its std, and a
# noise-free simulation would otherwise be judged against its rounding errors.
ACTIVITY_FLOOR_SHARE = 0.005

# Rounds of detect, leave out, refit: a long burst pulls the first fit, which hides part of it.
ROUNDS = 3


def _detect(stage: Stage, residual: np.ndarray) -> Activity:
    data = stage.data
    rms = np.sqrt(np.nanmean(data.tau_nm**2, axis=0))
    floor = np.maximum(ACTIVITY_FLOOR_SHARE * rms, MIN_OUTLIER_NM)
    return active_stretches(data.t_ns, data.q_rad, data.velocity_rad_s, residual, floor, stage.config.activity)


def _merged(first: Activity, second: Activity) -> Activity:
    """Both sets of stretches (the second found after the first's were left out)."""
    spans = tuple(sorted((*first.spans_s, *second.spans_s)))
    return Activity(
        active=first.active | second.active,
        spans_s=spans,
        peak_nm=np.maximum(first.peak_nm, second.peak_nm),
    )


def _finding(stage: Stage, activity: Activity) -> Finding:
    """The note of the stretches left out, or the problem where too little of the session is left."""
    duration_s = float(stage.data.t_ns[-1] - stage.data.t_ns[0]) * 1e-9
    worst = int(np.argmax(activity.peak_nm))
    if activity.share > stage.config.activity.max_active_share:
        values = {
            "relaxed_s": duration_s * (1.0 - activity.share),
            "relaxed_percent": 100.0 * (1.0 - activity.share),
            "n_stretches": len(activity.spans_s),
        }
        return Finding(code=FindingCode.TOO_LITTLE_RELAXED, values=values)
    values = {
        "n_stretches": len(activity.spans_s),
        "active_s": activity.active_s,
        "active_percent": 100.0 * activity.share,
        "peak_nm": float(activity.peak_nm[worst]),
    }
    return Finding(code=FindingCode.ARM_ACTIVE, where=joints_for(stage.n)[worst], values=values)


def leave_out_activity(stage: Stage) -> Stage:
    """Stretches where the arm was active (:func:`active_stretches`) are left out of every joint's rows and the
    model refitted; too much activity leaves too little of a relaxed arm to identify (invalid)."""
    if not stage.config.check_activity:
        return stage
    activity = _detect(stage, stage.fit.residual)
    if not activity.spans_s:
        return stage
    data, config, samples = stage.data, stage.config, stage.samples
    for round_ in range(ROUNDS):
        rows = samples.rows & ~activity.active[:, None]
        problem = build_problem(data, config.passive, rows, None, samples.extras)
        fit = fit_problem(problem)
        if round_ == ROUNDS - 1:
            break
        more = _detect(stage, fit.residual)
        if not more.spans_s:
            break
        activity = _merged(activity, more)
    finding = _finding(stage, activity)
    if finding.code is FindingCode.TOO_LITTLE_RELAXED or (rows.sum(axis=0) < len(problem.names)).any():
        return stage.apply(Outcome(problems=(finding,)))
    kept = dataclasses.replace(samples, rows=rows, problem=problem)
    stage = dataclasses.replace(stage, samples=kept)
    return stage.apply(Outcome(problem=problem, fit=fit, notes=(finding,)))
