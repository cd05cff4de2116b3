"""The fitting steps of the stacked identification: friction transitions, the passive model, far-off samples, and
the covariance terms of friction shape, marker placement, model choice and drift."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.joint.drift import drift_check, drift_columns
from bsp_ros.core.identification.joint.outliers import (
    GAP_EDGE_S,
    far_off_problem,
    fit_outliers,
    near_gaps,
    too_far_off,
)
from bsp_ros.core.identification.joint.placement_covariance import placement_covariance, placement_effect
from bsp_ros.core.identification.joint.stage import Outcome, Stage
from bsp_ros.core.identification.joint.transition import transition_widths
from bsp_ros.core.identification.ledger import Term
from bsp_ros.core.identification.selection import Candidate, Selection, select_passive, shape_probe, spread_covariance
from bsp_ros.core.identification.stacked import Fit, Problem, build_problem, fit_problem, residual_covariance
from bsp_ros.core.streams import joints_for

__all__ = [
    "add_friction_shape",
    "add_marker_placement",
    "add_model_choice",
    "choose_passive_model",
    "fit_friction_transitions",
    "model_drift",
    "prior_share",
    "remove_far_off_samples",
    "with_drift_terms",
    "with_placement",
]


def prior_share(problem: Problem, covariance: np.ndarray) -> dict[str, float]:
    """Posterior / prior variance of every parameter with a prior: near 1, the prior alone decided it."""
    out = {}
    for i in np.flatnonzero(problem.prior_precision > 0):
        key, owner = problem.names[i]
        out[f"{key}/{owner}"] = float(covariance[i, i] * problem.prior_precision[i])
    return out


def fit_friction_transitions(stage: Stage) -> Stage:
    """Where friction changes direction smoothly, fit its transition width; a joint that hardly leaves it gets the
    amplitudes over every plausible width in its Coulomb amplitude's std."""
    data, config, rows, usable = stage.data, stage.config, stage.samples.rows, stage.samples.usable
    widths, spread, span = transition_widths(stage.problem, stage.fit, data, config)
    if not widths.any():
        return dataclasses.replace(stage, widths_rad_s=widths, spread_nm=spread)
    problem = build_problem(data, config.passive, rows, widths, stage.samples.extras)
    notes = []
    for j, joint in enumerate(joints_for(stage.n)):
        if widths[j] == 0:
            continue
        beyond = float((np.abs(data.velocity_rad_s[rows[:, j], j]) > 3 * widths[j]).sum()) / max(usable, 1)
        values = {"width_mrad_s": float(1e3 * widths[j]), "beyond_percent": 100 * beyond}
        notes.append(Finding(code=FindingCode.FRICTION_SMOOTH, where=joint, values=values))
        if beyond < config.min_row_share:
            # Weakly identified, not wrong: every width from the sign step to the chosen one stays plausible,
            # and the amplitudes over them join its std.
            spread[j] = max(spread[j], span[j])
            values = {"beyond_percent": 100 * beyond}
            notes.append(Finding(code=FindingCode.FRICTION_TRANSITION_WEAK, where=joint, values=values))
    refit = fit_problem(problem)
    stage = stage.apply(Outcome(problem=problem, fit=refit, notes=tuple(notes)))
    return dataclasses.replace(stage, widths_rad_s=widths, spread_nm=spread)


def with_placement(stage: Stage, candidate: Problem, candidate_fit: Fit) -> np.ndarray:
    """A candidate fit's covariance with the marker placement's share (what candidates are compared with)."""
    if not stage.placement_sd_m.any():
        return candidate_fit.covariance
    return candidate_fit.covariance + placement_covariance(stage.data, candidate, candidate_fit, stage.placement_sd_m)


def _fitted_widths(stage: Stage) -> np.ndarray | None:
    return stage.widths_rad_s if stage.widths_rad_s.any() else None


def choose_passive_model(stage: Stage) -> Stage:
    """With ``--passive auto``, the passive model the data choose; the models the std must cover (the choice, or a
    fixed nonlinear model probed like a chosen one: its static moments may hang on its assumed shape)."""
    data, config, rows, extras = stage.data, stage.config, stage.samples.rows, stage.samples.extras
    if config.passive.select:
        selection = select_passive(
            data, config.passive, rows, _fitted_widths(stage), extras, functools.partial(with_placement, stage)
        )
        assert selection.chosen.problem is not None and selection.chosen.fit is not None
        chosen = dataclasses.replace(config, passive=selection.chosen.model)
        stage = dataclasses.replace(stage, config=chosen, selection=selection, probed=selection)
        return stage.apply(Outcome(problem=selection.chosen.problem, fit=selection.chosen.fit))
    if "nonlinear" in config.passive.terms:
        fixed = Candidate(config.passive, stage.problem, stage.fit, 0.0, 1.0, 1.0)
        probe = shape_probe(data, fixed, rows, _fitted_widths(stage), extras)
        return dataclasses.replace(stage, probed=Selection(fixed, [fixed], probe))
    return stage


def remove_far_off_samples(stage: Stage) -> Stage:
    """Samples far off the fit are removed and the model refitted; too many mean the model does not fit, and an
    estimate their removal moves by more than ``max_outlier_shift`` std hangs on them."""
    config, fit, usable = stage.config, stage.fit, stage.samples.usable
    far = fit_outliers(fit, config)
    n_far = int(far.sum())
    if too_far_off(n_far, usable):
        return stage.apply(Outcome(problems=(far_off_problem(n_far, usable, config),)))
    if not n_far:
        return stage
    rows = stage.samples.rows & ~far[:, None]
    kept = build_problem(stage.data, config.passive, rows, stage.widths_rad_s, stage.samples.extras)
    refit = fit_problem(kept)
    # Against the larger std of the two fits: samples far off the fit (a filter's edge, a glitch) also inflate the
    # std of the fit that keeps them.
    std = np.sqrt(np.clip(np.maximum(np.diag(refit.covariance), np.diag(fit.covariance)), 0.0, None))
    shift = np.abs(refit.values - fit.values) / np.maximum(std, 1e-300)
    near_gap = int((far & near_gaps(stage.data.t_ns, GAP_EDGE_S)).sum())
    removed = Finding(
        code=FindingCode.FIT_OUTLIERS_REMOVED,
        values={"n": n_far, "outlier_sd": config.outlier_sd, "near_gap": near_gap, "gap_edge_s": GAP_EDGE_S},
    )
    problems: tuple[Finding, ...] = ()
    if shift.max() > config.max_outlier_shift:
        worst = int(np.argmax(shift))
        key, owner = stage.problem.names[worst]
        hangs = {"n_far": n_far, "key": key, "shift_sd": float(shift[worst])}
        problems = (Finding(code=FindingCode.HANGS_ON_FEW_SAMPLES, where=owner, values=hangs),)
    stage = stage.apply(Outcome(problem=kept, fit=refit, notes=(removed,), problems=problems))
    return dataclasses.replace(stage, sample_notes=(*stage.sample_notes, removed), removed=n_far)


def add_friction_shape(stage: Stage) -> Stage:
    """Whether friction steps or changes smoothly at low speed is itself uncertain: its effect on each Coulomb
    amplitude joins that amplitude's variance (independent of the other parameters). Then the prior's share of each
    parameter, judged before the placement uncertainty is added."""
    if stage.spread_nm.any():
        term = np.zeros_like(stage.fit.covariance)
        for j in range(stage.n):
            index = stage.config.passive.local_column("coulomb", stage.n, j)
            term[index, index] = stage.spread_nm[j] ** 2
        stage = stage.apply(Outcome(added=((Term.FRICTION_SHAPE, term),)))
    return dataclasses.replace(stage, prior_share=prior_share(stage.problem, stage.fit.covariance))


def add_marker_placement(stage: Stage) -> Stage:
    """How far each chain point may sit from where the data put it (skin markers, the robot's contact point): its
    effect on the estimate joins the covariance, and the misfit check judges the residual it leaves.

    The sensor-noise term is then the HAC sandwich of that residual: the part of the offsets' effect the model
    cannot follow would otherwise be counted twice, once as noise and once as placement (on a planned protocol
    with 2 mm offsets the Coulomb amplitudes' noise term was 12-47 times the exact-marker one; bench
    placement_sharpness.py).
    """
    if not stage.placement_sd_m.any():
        return dataclasses.replace(stage, placement_fit=stage.fit)
    placement = placement_effect(stage.data, stage.problem, stage.fit, stage.placement_sd_m)
    placed = dataclasses.replace(
        stage, placement=placement, placement_fit=stage.fit, judged_residual=placement.residual
    )
    fit = stage.fit
    noise, _ = residual_covariance(stage.problem, fit.design, fit.weights, placement.residual)
    raw = stage.ledger.get(Term.SENSOR_NOISE)
    assert raw is not None  # every stage's ledger starts with the fit's own covariance
    raw_variance = np.diag(raw)
    ratio = np.divide(np.diag(noise), raw_variance, out=np.ones_like(raw_variance), where=raw_variance > 0)
    placed = dataclasses.replace(placed, noise_scale=np.sqrt(np.clip(ratio, 0.0, None)))
    return placed.apply(
        Outcome(added=((Term.MARKER_PLACEMENT, placement.covariance),), replaced=((Term.SENSOR_NOISE, noise),))
    )


def add_model_choice(stage: Stage) -> Stage:
    """What the choice of passive model leaves open joins the std (model-averaged variance)."""
    if stage.probed is None:
        return stage
    columns = None if stage.placement is None else stage.placement.columns
    residual = None if stage.placement is None else stage.placement.residual
    spread, shift = spread_covariance(stage.probed, columns, residual)
    notes = tuple(
        Finding(
            code=FindingCode.MODEL_CHOICE_SPREAD,
            where=stage.problem.names[index][1],
            values={"shift_sd": float(shift[index])},
        )
        for index in np.flatnonzero(shift[: stage.n] > 0.5).tolist()
    )
    return stage.apply(Outcome(added=((Term.MODEL_CHOICE, spread),), notes=notes))


def with_drift_terms(stage: Stage) -> Stage:
    """``stage`` with a drift's columns (computed once: the drift check and the placement check both fit them)."""
    if stage.drift_terms is not None:
        return stage
    return dataclasses.replace(stage, drift_terms=drift_columns(stage.data))


def model_drift(stage: Stage) -> Stage:
    """Before the fit is judged: a drifting sensor leaves a slow residual that would otherwise read as a model that
    does not fit (the quieter the sensor, the sooner). One refit: a live window runs it on every update."""
    config = stage.config
    if not (config.check_elastic or config.check_drift) or stage.problems:
        return stage
    stage = with_drift_terms(stage)
    assert stage.drift_terms is not None
    drift = drift_check(stage.data, stage.problem, stage.fit, stage.drift_terms)
    if drift is None:
        return stage
    judged = stage.judged_residual
    if judged is not None:
        judged = judged - (stage.fit.residual - drift.fit.residual)
    level = drift.fit.covariance - drift.own_covariance
    own_covariance = drift.own_covariance
    if stage.noise_scale is not None:  # the noise the offsets leave, as add_marker_placement measured it
        own_covariance = own_covariance * np.outer(stage.noise_scale, stage.noise_scale)
    own = dataclasses.replace(drift.fit, covariance=own_covariance)
    stage = stage.apply(Outcome(fit=own, added=((Term.DRIFT, level),), notes=(drift.note,)))
    return dataclasses.replace(stage, drift=drift, judged_residual=judged)
