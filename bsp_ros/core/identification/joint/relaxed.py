"""The steps that keep the relaxed arm of a session: stretches of muscle activity are found and left out, and a
hand that slipped in the handle is followed."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.activity import Activity, active_stretches
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.contact_slip import (
    FOLLOW_KNOT_S,
    MIN_SLIP_M,
    Travel,
    contact_slip,
    fit_travel,
    monotone_travel,
    refined_knots,
    slip_lever_n,
    slip_spans,
)
from bsp_ros.core.identification.joint.emg_activity import emg_evidence, emg_values, with_emg
from bsp_ros.core.identification.joint.misfit import misfit_against_noise
from bsp_ros.core.identification.joint.outliers import MIN_OUTLIER_NM, fit_outliers, too_far_off
from bsp_ros.core.identification.joint.placement_covariance import offset_columns
from bsp_ros.core.identification.joint.stage import Outcome, Stage
from bsp_ros.core.identification.ledger import Term
from bsp_ros.core.identification.stacked import build_problem, fit_problem
from bsp_ros.core.streams import joints_for

__all__ = [
    "ACTIVITY_FLOOR_SHARE",
    "MIN_SLIP_M",
    "activity_finding",
    "add_contact_slip",
    "detect_activity",
    "follow_the_hand",
    "leave_out_activity",
]

# A step of the travel: at least this far between two of its knots, m. The hand's jerk at a slip turns joints
# that moved slowly (their dry friction flips for a moment: a Nm at the shoulder on the MuJoCo slipping hand),
# which no travel holds; the stretches that stand off the fit there are left out of every joint's rows.
SLIP_STEP_M = 0.001

# Activity below this share of a joint's RMS torque is not looked for: it moves no estimate beyond its std, and a
# noise-free simulation would otherwise be judged against its rounding errors.
ACTIVITY_FLOOR_SHARE = 0.005

# Rounds of detect, leave out, refit: a long burst pulls the first fit, which hides part of it.
ROUNDS = 3


def detect_activity(data: IdentificationData, config: JointConfig, residual: np.ndarray) -> Activity:
    """:func:`active_stretches` of ``data`` from a fit's ``residual`` (N, n), below the floor nothing."""
    rms = np.sqrt(np.nanmean(data.tau_nm**2, axis=0))
    floor = np.maximum(ACTIVITY_FLOOR_SHARE * rms, MIN_OUTLIER_NM)
    return active_stretches(data.t_ns, data.q_rad, data.velocity_rad_s, residual, floor, config.activity)


def _merged(first: Activity, second: Activity) -> Activity:
    """Both sets of stretches (the second found after the first's were left out)."""
    spans = tuple(sorted((*first.spans_s, *second.spans_s)))
    return Activity(
        active=first.active | second.active,
        spans_s=spans,
        peak_nm=np.maximum(first.peak_nm, second.peak_nm),
    )


def activity_finding(
    data: IdentificationData, config: JointConfig, activity: Activity, emg: Mapping[str, float | str] | None = None
) -> Finding:
    """The note of the stretches left out, or the problem where too little of the session is left; ``emg``: what
    the EMG showed beside the torque (:func:`emg_values`), where the session has usable EMG."""
    duration_s = float(data.t_ns[-1] - data.t_ns[0]) * 1e-9
    worst = int(np.argmax(activity.peak_nm))
    if activity.share > config.activity.max_active_share:
        values = {
            "relaxed_s": duration_s * (1.0 - activity.share),
            "relaxed_percent": 100.0 * (1.0 - activity.share),
            "n_stretches": len(activity.spans_s),
            **(emg or {}),
        }
        return Finding(code=FindingCode.TOO_LITTLE_RELAXED, values=values)
    values = {
        "n_stretches": len(activity.spans_s),
        "active_s": activity.active_s,
        "active_percent": 100.0 * activity.share,
        "peak_nm": float(activity.peak_nm[worst]),
        **(emg or {}),
    }
    where = joints_for(data.n_joints)[worst] if activity.peak_nm[worst] > 0 else ""
    return Finding(code=FindingCode.ARM_ACTIVE, where=where, values=values)


# Samples far off the fit beyond this share of the usable ones, with a residual above the noise, are the mark of
# bursts: a burst stands many robust sd off a fit of the relaxed arm, a model's smooth shortfall does not.
MIN_FAR_SHARE = 0.01


def _calls_for_activity(stage: Stage) -> bool:
    """Whether the fit shows the mark of bursts: too many samples far off it, or some (``MIN_FAR_SHARE``) with a
    residual above the noise at a joint. A model's own smooth shortfall (an elastic moment it lacks, a
    musculoskeletal arm's passive muscles on a trajectory that never comes back) leaves none far off, and leaving
    stretches of it out would hide it from the checks that follow."""
    n_far = int(fit_outliers(stage.fit, stage.config).sum())
    usable = stage.samples.usable
    if too_far_off(n_far, usable):
        return True
    _, misfit = misfit_against_noise(stage.fit)
    return n_far > MIN_FAR_SHARE * usable and bool((misfit > stage.config.max_misfit).any())


def leave_out_activity(stage: Stage) -> Stage:
    """Stretches where the arm was active (:func:`active_stretches`) are left out of every joint's rows and the
    model refitted; too much activity leaves too little of a relaxed arm to identify (invalid). Only where the fit
    shows the mark of bursts (:func:`_calls_for_activity`). Where the session has EMG, the stretches it shows active
    (:func:`emg_evidence`) are left out too, bursts of torque or not: the clinician's definition of not relaxed."""
    if not stage.config.check_activity:
        return stage
    evidence = emg_evidence(stage.data, stage.config.emg)
    if evidence is not None and evidence.notes:
        stage = stage.apply(Outcome(notes=evidence.notes))
    emg_active = np.zeros(stage.data.t_ns.size, dtype=bool) if evidence is None else evidence.active
    from_torque = _calls_for_activity(stage)
    if not from_torque and not emg_active.any():
        return stage
    data, config, samples = stage.data, stage.config, stage.samples
    activity = (
        detect_activity(data, config, stage.fit.residual)
        if from_torque
        else Activity(active=np.zeros(data.t_ns.size, dtype=bool), spans_s=(), peak_nm=np.zeros(data.n_joints))
    )
    if not activity.spans_s and not emg_active.any():
        return stage
    for round_ in range(ROUNDS):
        rows = samples.rows & ~(activity.active | emg_active)[:, None]
        problem = build_problem(data, config.passive, rows, None, samples.extras)
        fit = fit_problem(problem)
        if round_ == ROUNDS - 1 or not from_torque:
            break
        more = detect_activity(data, config, fit.residual)
        if not more.spans_s:
            break
        activity = _merged(activity, more)
    emg = None
    if evidence is not None and evidence.activity is not None:
        emg = emg_values(activity.active, emg_active, evidence.activity)
        activity = with_emg(activity, evidence, data.t_ns)
    finding = activity_finding(data, config, activity, emg)
    if finding.code is FindingCode.TOO_LITTLE_RELAXED or (rows.sum(axis=0) < len(problem.names)).any():
        return stage.apply(Outcome(problems=(finding,)))
    kept = dataclasses.replace(samples, rows=rows, problem=problem)
    stage = dataclasses.replace(stage, samples=kept)
    return stage.apply(Outcome(problem=problem, fit=fit, notes=(finding,)))


def _jerks(stage: Stage, rows: np.ndarray, travel: Travel, lever_n: np.ndarray) -> np.ndarray:
    """(N,) the seconds about a slip where the hand's jerk leaves torque no travel holds: the stretches the activity
    detector finds on ``rows`` once ``travel`` is taken out, where they lie within a knot of one of its steps
    (bursts elsewhere are left to :func:`leave_out_activity`)."""
    data, config = stage.data, stage.config
    held = dataclasses.replace(data, tau_nm=data.tau_nm - (travel.travel_m * lever_n)[:, None])
    fit = fit_problem(build_problem(held, config.passive, rows, None, stage.samples.extras))
    found = detect_activity(held, config, fit.residual)
    reach_s = float(np.diff(travel.knots_s).max())
    steps = slip_spans(monotone_travel(travel, data.t_ns), SLIP_STEP_M)
    t_s = (data.t_ns - data.t_ns[0]) * 1e-9
    jerked = np.zeros(t_s.size, dtype=bool)
    for start, end in found.spans_s:
        if any(start < step_end + reach_s and end > step_start - reach_s for step_start, step_end in steps):
            jerked |= (t_s >= start) & (t_s <= end)
    return jerked


def _offsets_beside_travel(stage: Stage) -> np.ndarray | None:
    """(N, n, m) the markers' offset columns a slip is looked for beside, or None without placement: every one but
    the contact point's along the hand, which is the travel itself held constant."""
    sd_m = stage.placement_sd_m
    if not sd_m.any():
        return None
    columns = offset_columns(stage.data, stage.problem, stage.fit, sd_m)
    per_recording = 2 * (stage.n + 1)
    keep = np.arange(columns.shape[2]) % per_recording != 2 * stage.n
    return columns[:, :, keep]


def follow_the_hand(stage: Stage) -> Stage:
    """A contact point that travelled along the hand (:func:`contact_slip`: found on knots 5 s apart) is followed:
    the travel is fitted with the arm's parameters on finer knots about its steps and made monotone, taken out of
    the torques, the seconds of each slip's jerk left out and the model refitted; the finding says by about how
    much the hand moved in the handle. A fallback that identifies the session afresh starts from the torques before
    (``Stage.unslipped``), and follows the hand with its own model."""
    if not stage.config.check_activity:
        return stage
    data, config = stage.data, stage.config
    lever = slip_lever_n(data.q_rad, data.lengths_m, data.tau_nm)
    slip = contact_slip(stage.problem, data.t_ns, lever)
    if slip.found:
        # Confirmed beside the markers' offsets, which a travel on a fast protocol can mimic (looked for beside
        # them only here: a session without a slip candidate spends nothing on their columns).
        slip = contact_slip(stage.problem, data.t_ns, lever, offsets=_offsets_beside_travel(stage))
    if not slip.found or slip.travel is None:
        return stage
    knots = refined_knots(slip.travel, SLIP_STEP_M, FOLLOW_KNOT_S)
    followed = monotone_travel(fit_travel(stage.problem, lever, data.t_ns, knots), data.t_ns)
    jerked = _jerks(stage, stage.samples.rows, followed, lever)
    rows = stage.samples.rows & ~jerked[:, None]
    travel = followed.travel_m
    held = dataclasses.replace(data, tau_nm=data.tau_nm - (travel * lever)[:, None])
    problem = build_problem(held, config.passive, rows, None, stage.samples.extras)
    fit = fit_problem(problem)
    # How the travel is followed is itself uncertain: its estimate on the coarser knots, and the travel counted
    # from its mean rather than the session's start (the hand may have settled before it), are the alternatives
    # whose fits' differences join the covariance once the passive model is chosen (:func:`add_contact_slip`).
    coarse = data.tau_nm - (slip.travel.travel_m * lever)[:, None]
    centred = data.tau_nm - ((travel - travel.mean()) * lever)[:, None]
    duration_s = float(data.t_ns[-1] - data.t_ns[0]) * 1e-9
    values = {
        "slip_mm": 1e3 * abs(float(travel[-1])),
        "trend_percent": 100.0 * slip.monotone_share,
        "left_out_s": float(jerked.mean()) * duration_s,
    }
    stage = dataclasses.replace(
        stage,
        data=held,
        unslipped=data,
        samples=dataclasses.replace(stage.samples, rows=rows, problem=problem),
        slip_alternatives=(coarse, centred),
    )
    found = Finding(code=FindingCode.HAND_SLIPPED, values=values)
    return stage.apply(Outcome(problem=problem, fit=fit, notes=(found,)))


def add_contact_slip(stage: Stage) -> Stage:
    """What following a slipping hand leaves open (:func:`follow_the_hand`'s alternatives, each fitted with the
    chosen passive model) joins the covariance as the ``contact_slip`` term: rank one per alternative, so that no
    check reads what the finest estimate of the travel leaves over as a property of the arm."""
    if not stage.slip_alternatives:
        return stage
    widths = stage.widths_rad_s if stage.widths_rad_s.any() else None
    term = np.zeros_like(stage.fit.covariance)
    for tau_nm in stage.slip_alternatives:
        other = dataclasses.replace(stage.data, tau_nm=tau_nm)
        problem = build_problem(other, stage.config.passive, stage.samples.rows, widths, stage.samples.extras)
        shift = fit_problem(problem).values - stage.fit.values
        term += np.outer(shift, shift)
    return stage.apply(Outcome(added=((Term.CONTACT_SLIP, term),)))
