"""The stacked identification of all joints: the fit, the model checks and the validity verdict, in order."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.covariance import correlation_from_covariance
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.elastic import ElasticReference
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.curves import curve_basis
from bsp_ros.core.identification.joint.drift import drift_check, drift_columns
from bsp_ros.core.identification.joint.elastic_check import elastic_check
from bsp_ros.core.identification.joint.held import HeldModel
from bsp_ros.core.identification.joint.misfit import misfit_against_noise
from bsp_ros.core.identification.joint.outliers import (
    GAP_EDGE_S,
    MIN_OUTLIER_NM,
    far_off_problem,
    fit_outliers,
    near_gaps,
    too_far_off,
)
from bsp_ros.core.identification.joint.passive_offset import passive_offset_sensitivity
from bsp_ros.core.identification.joint.placement_covariance import (
    covariance_from_products,
    placement_covariance,
    placement_effect,
)
from bsp_ros.core.identification.joint.placement_scale import placement_scale
from bsp_ros.core.identification.joint.samples import usable_samples
from bsp_ros.core.identification.joint.stribeck import stribeck_check
from bsp_ros.core.identification.joint.torque_response import TorqueResponse
from bsp_ros.core.identification.joint.transition import transition_widths
from bsp_ros.core.identification.priors import implausible_perpendicular_moments
from bsp_ros.core.identification.result import IdentificationResult, ParameterName
from bsp_ros.core.identification.selection import Candidate, Selection, select_passive, shape_probe, spread_covariance
from bsp_ros.core.identification.stacked import Fit, Problem, build_problem, fit_problem, reweighted_values
from bsp_ros.core.streams import joints_for

# Above this column-scaled condition number no std is meaningful: parameters the motion cannot tell apart.
UNIDENTIFIABLE_CONDITION = 1e8


def unidentifiable_problem(condition: float) -> Finding:
    """The problem of a fit whose column-scaled condition number is above :data:`UNIDENTIFIABLE_CONDITION`."""
    return Finding(code=FindingCode.NOT_IDENTIFIABLE, values={"condition": float(condition)})


def prior_share(problem: Problem, covariance: np.ndarray) -> dict[str, float]:
    """Posterior / prior variance of every parameter with a prior: near 1, the prior alone decided it."""
    out = {}
    for i in np.flatnonzero(problem.prior_precision > 0):
        key, owner = problem.names[i]
        out[f"{key}/{owner}"] = float(covariance[i, i] * problem.prior_precision[i])
    return out


def _unbounded_static_moments(problem: Problem) -> np.ndarray:
    """(p,) the fit of ``problem`` with the static moments' lower bound 0 lifted: the data's own estimate."""
    n = problem.torque.shape[1]
    lower = np.where(np.arange(len(problem.names)) < n, -np.inf, problem.lower)
    return reweighted_values(dataclasses.replace(problem, lower=lower)).values


def failed_result(
    data: IdentificationData, names: list[ParameterName], problems: list[Finding], warnings: list[Finding]
) -> IdentificationResult:
    """An invalid result: NaN values and covariance, with ``problems`` (invalid findings) and ``warnings``."""
    p = len(names)
    return IdentificationResult(
        method="joint",
        names=names,
        values=np.full(p, np.nan),
        covariance=np.full((p, p), np.nan),
        findings=(*problems, *warnings),
        n_samples=int(data.t_ns.size),
    )


def _family_result(data: IdentificationData, config: JointConfig) -> IdentificationResult:
    """``data`` identified with the elastic family the data choose from (``--passive auto``) in place of ``config``'s
    fixed passive model, and no further fallback."""
    chosen = dataclasses.replace(config.passive, select=True)
    return identify_joint(data, dataclasses.replace(config, passive=chosen, elastic_fallback=False))


def _elastic_family_fit(
    data: IdentificationData, config: JointConfig, misfits: list[Finding]
) -> IdentificationResult | None:
    """Where the fixed passive model does not fit (``misfits``: per joint; nothing else is wrong), the elastic
    family the data choose from (``--passive auto``), if it fits and is valid; None otherwise.

    A spring the fixed model lacks leaves a residual far above the sensor noise: the elastic check, which would
    find it, runs only on a model that fits. On a MuJoCo arm with joint springs and a planned trajectory the
    default model was invalid here ("does not fit at the wrist", static moments 4.7 std off) while the family was
    valid within 1.5 std (bench/README.md, physics engine). A misfit the family cannot take up (a wrong
    sensor transform, a load, low-speed friction) leaves it invalid too, and the fixed model's verdict stands.
    """
    if "offset" in config.passive.terms:  # an elastic model already: nothing wider to choose from
        return None
    family = _family_result(data, config)
    if not family.valid:
        return None
    values = {
        "model": config.passive.label,
        "joints": tuple(f.where for f in misfits),
        **{key: tuple(float(f.values[key]) for f in misfits) for key in ("rms_nm", "ratio", "noise_nm")},
    }
    return family.with_findings(Finding(code=FindingCode.ELASTIC_FAMILY_CHOSEN, values=values), first=True)


def identify_joint(data: IdentificationData, config: JointConfig | None = None) -> IdentificationResult:
    """Identify static moments and passive moments of all joints in one stacked problem.

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
    IdentificationResult with a HAC covariance; ``valid`` False with a message when excitation is poor.
    """
    config = config or JointConfig()
    n = data.n_joints
    joints = joints_for(n)
    # How far each chain point may sit from where the data put it (skin markers; the robot's contact point).
    placement_sd_m = config.placement_sd_m(n, data.contact_from_robot)
    samples = usable_samples(data, config)
    rows, spikes, extras, problem = samples.rows, samples.spikes, samples.extras, samples.problem
    problems, warnings = list(samples.problems), list(samples.warnings)
    # The notes so far are the samples'; those added below are the model's (held between a live window's checks),
    # but for the samples' own notes among them (``sample_notes``).
    data_notes: int = len(warnings)
    sample_notes: list[Finding] = []
    if samples.too_few is not None:
        return failed_result(data, problem.names, problems or [samples.too_few], warnings)
    usable = samples.usable
    if "coulomb" in config.passive.terms:
        for j, joint in enumerate(joints):
            share = rows[:, j].sum() / max(usable, 1)
            if share < config.min_row_share:
                problems.append(
                    Finding(
                        code=FindingCode.DIRECTION_UNCLEAR, where=joint, values={"share_percent": float(100 * share)}
                    )
                )
    fit = fit_problem(problem)
    widths, spread, span = transition_widths(problem, fit, data, config)
    if widths.any():
        problem = build_problem(data, config.passive, rows, widths, extras)
        fit = fit_problem(problem)
        for j, joint in enumerate(joints):
            if widths[j] == 0:
                continue
            beyond = float((np.abs(data.velocity_rad_s[rows[:, j], j]) > 3 * widths[j]).sum()) / max(usable, 1)
            warnings.append(
                Finding(
                    code=FindingCode.FRICTION_SMOOTH,
                    where=joint,
                    values={"width_mrad_s": float(1e3 * widths[j]), "beyond_percent": 100 * beyond},
                )
            )
            if beyond < config.min_row_share:
                # Weakly identified, not wrong: every width from the sign step to the chosen one stays plausible,
                # and the amplitudes over them join its std.
                spread[j] = max(spread[j], span[j])
                warnings.append(
                    Finding(
                        code=FindingCode.FRICTION_TRANSITION_WEAK, where=joint, values={"beyond_percent": 100 * beyond}
                    )
                )
    selection = None
    fitted_widths = widths if widths.any() else None

    def with_placement(candidate: Problem, candidate_fit: Fit) -> np.ndarray:
        if not placement_sd_m.any():
            return candidate_fit.covariance
        return candidate_fit.covariance + placement_covariance(data, candidate, candidate_fit, placement_sd_m)

    if config.passive.select:
        selection = select_passive(data, config.passive, rows, fitted_widths, extras, with_placement)
        assert selection.chosen.problem is not None and selection.chosen.fit is not None
        config = dataclasses.replace(config, passive=selection.chosen.model)
        problem, fit = selection.chosen.problem, selection.chosen.fit
    # The models the estimate's std must cover: the data's choice, or a fixed nonlinear model probed like a chosen
    # one (its static moments may hang on its assumed shape).
    probed = selection
    if selection is None and "nonlinear" in config.passive.terms:
        fixed = Candidate(config.passive, problem, fit, 0.0, 1.0, 1.0)
        probed = Selection(fixed, [fixed], shape_probe(data, fixed, rows, fitted_widths, extras))
    far = fit_outliers(fit, config)
    n_far = int(far.sum())
    n_removed = 0
    if too_far_off(n_far, usable):
        problems.append(far_off_problem(n_far, usable, config))
    elif n_far:
        kept = build_problem(data, config.passive, rows & ~far[:, None], widths, extras)
        refit = fit_problem(kept)
        # Against the larger std of the two fits: samples far off the fit (a filter's edge, a glitch) also
        # inflate the std of the fit that keeps them.
        std = np.sqrt(np.clip(np.maximum(np.diag(refit.covariance), np.diag(fit.covariance)), 0.0, None))
        shift = np.abs(refit.values - fit.values) / np.maximum(std, 1e-300)
        near_gap = int((far & near_gaps(data.t_ns, GAP_EDGE_S)).sum())
        sample_notes.append(
            Finding(
                code=FindingCode.FIT_OUTLIERS_REMOVED,
                values={"n": n_far, "outlier_sd": config.outlier_sd, "near_gap": near_gap, "gap_edge_s": GAP_EDGE_S},
            )
        )
        warnings.append(sample_notes[-1])
        if shift.max() > config.max_outlier_shift:
            worst = int(np.argmax(shift))
            key, owner = problem.names[worst]
            problems.append(
                Finding(
                    code=FindingCode.HANGS_ON_FEW_SAMPLES,
                    where=owner,
                    values={"n_far": n_far, "key": key, "shift_sd": float(shift[worst])},
                )
            )
        problem, fit, n_removed = kept, refit, n_far
    # The fit's own covariance: what is added to it below (friction shape, placement, model choice) must survive
    # a refit that models a drift.
    own_covariance = fit.covariance
    if spread.any():
        # Whether friction steps or changes smoothly at low speed is itself uncertain: its effect on each
        # Coulomb amplitude joins that amplitude's variance (independent of the other parameters).
        covariance = fit.covariance.copy()
        k = len(config.passive.local)
        for j in range(n):
            index = n + j * k + config.passive.local.index("coulomb")
            covariance[index, index] += spread[j] ** 2
        fit = dataclasses.replace(fit, covariance=covariance)
    # Whether the data or the prior decided a parameter, judged before the placement uncertainty is added.
    shares = prior_share(problem, fit.covariance)
    judged_residual = None
    placement_share = np.zeros_like(fit.covariance)
    placement = None
    placement_fit = fit  # what the placement's share is computed at (before a drift is modelled)
    if placement_sd_m.any():
        placement = placement_effect(data, problem, fit, placement_sd_m)
        fit = dataclasses.replace(fit, covariance=fit.covariance + placement.covariance)
        judged_residual = placement.residual
        placement_share = placement.covariance
    model_spread = np.zeros_like(fit.covariance)
    if probed is not None:
        # What the choice of passive model leaves open belongs in the std (model-averaged variance).
        model_spread, model_shift = spread_covariance(probed)
        fit = dataclasses.replace(fit, covariance=fit.covariance + model_spread)
        for index in np.flatnonzero(model_shift[:n] > 0.5).tolist():
            warnings.append(
                Finding(
                    code=FindingCode.MODEL_CHOICE_SPREAD,
                    where=problem.names[index][1],
                    values={"shift_sd": float(model_shift[index])},
                )
            )
    drift = None
    # A drift's columns, computed once where the drift check and the placement check both need them.
    drift_terms = functools.cache(functools.partial(drift_columns, data))
    if (config.check_elastic or config.check_drift) and not problems:
        # Before the fit is judged: a drifting sensor leaves a slow residual that would otherwise read as a model
        # that does not fit (the quieter the sensor, the sooner). One refit: a live window runs it on every update.
        drift = drift_check(data, problem, fit, drift_terms())
        if drift is not None:
            if judged_residual is not None:
                judged_residual = judged_residual - (fit.residual - drift.fit.residual)
            added = fit.covariance - own_covariance
            fit = dataclasses.replace(drift.fit, covariance=drift.fit.covariance + added)
            own_covariance = drift.own_covariance
            warnings.append(drift.note)
    reference = ElasticReference.from_angles(data.passive_q_rad)
    basis = curve_basis(data, reference, fit, probed)
    curves = {} if basis is None else basis.curves(fit)
    noise, misfit = misfit_against_noise(fit, judged_residual)
    # Per joint that does not fit: how (its residual RMS against the sensor noise).
    misfits = [
        Finding(
            code=FindingCode.MODEL_MISFIT,
            where=joint,
            values={"rms_nm": float(misfit[j] * noise[j]), "ratio": float(misfit[j]), "noise_nm": float(noise[j])},
        )
        for j, joint in enumerate(joints)
        if misfit[j] > config.max_misfit and misfit[j] * noise[j] > MIN_OUTLIER_NM
    ]
    if misfits and not problems and config.elastic_fallback and config.check_elastic and selection is None:
        family = _elastic_family_fit(data, config, misfits)
        if family is not None:
            return family
    problems += misfits
    if fit.condition > UNIDENTIFIABLE_CONDITION:
        problems.append(unidentifiable_problem(fit.condition))
    elif fit.condition > config.max_condition:
        # An honest std is large here, not wrong: the estimate stays, its std says what the motion leaves open.
        warnings.append(
            Finding(
                code=FindingCode.POORLY_EXCITED,
                values={"condition": float(fit.condition), "max_condition": config.max_condition},
            )
        )
    correlation = correlation_from_covariance(fit.covariance)
    all_std = np.sqrt(np.clip(np.diag(fit.covariance), 0.0, None))
    max_corr_with_gravity = {}
    unbounded: np.ndarray | None = None  # fitted on the first static moment at its bound, once
    for i, (key, owner) in enumerate(problem.names[: problem.passive_end]):
        if i >= n:
            partner = int(np.argmax(np.abs(correlation[i, :n])))
            corr = float(abs(correlation[i, partner]))
            max_corr_with_gravity[f"{key}/{owner}"] = corr
            value = fit.values[partner]
            rel_std = all_std[partner] / value if value > 0 else np.inf
            if corr > config.confounded_corr and rel_std > config.confounded_rel_std:
                warnings.append(
                    Finding(
                        code=FindingCode.CONFOUNDED,
                        where=owner,
                        values={
                            "key": key,
                            "corr": corr,
                            "segment": problem.names[partner][1],
                            "rel_std": float(rel_std),
                        },
                    )
                )
        std = all_std[i]
        at_bound = np.isfinite(problem.lower[i]) and fit.values[i] <= problem.lower[i] + 1e-12
        if at_bound and i < n:
            if unbounded is None:
                unbounded = _unbounded_static_moments(problem)
            own = unbounded[i]
            if own + 3.0 * std < 0.0:
                problems.append(Finding(code=FindingCode.STATIC_MOMENT_AT_BOUND, where=owner))
            else:
                # The data's own (unbounded) estimate lies within 3 std of 0: the motion leaves this static moment
                # open (one posture, the elastic family), which its std says; no evidence of a fault.
                warnings.append(
                    Finding(code=FindingCode.STATIC_MOMENT_OPEN, where=owner, values={"own_kgm": float(own)})
                )
        elif at_bound and std > 0:
            warnings.append(
                Finding(
                    code=FindingCode.PARAMETER_AT_BOUND,
                    where=owner,
                    values={"key": key, "lower": float(problem.lower[i])},
                )
            )
        if i < n and fit.values[i] > 0 and std > 0.5 * fit.values[i]:
            warnings.append(
                Finding(
                    code=FindingCode.UNCERTAIN_STATIC_MOMENT,
                    where=owner,
                    values={"value_kgm": float(fit.values[i]), "std_kgm": float(std)},
                )
            )
    data_problems = len(problems)  # those below come from the model checks (held between a live window's checks)
    if config.check_elastic and not problems:
        stribeck = stribeck_check(data, problem, fit, config, widths)
        unmodelled = [f.note for f in stribeck if f.biases_estimate]
        warnings += unmodelled + [f.note for f in stribeck if not f.biases_estimate]
        if unmodelled:
            problems.append(Finding(code=FindingCode.UNMODELLED_EFFECT))
        covariance = fit.covariance.copy()
        for finding in (f for f in stribeck if not f.biases_estimate):
            # Which friction law holds at low speed is open; the amplitudes of both join the Coulomb variance.
            covariance[finding.coulomb_column, finding.coulomb_column] += finding.coulomb_shift_nm**2
        fit = dataclasses.replace(fit, covariance=covariance)
    # The model with a linear spring's terms beside this one's: the elastic check's wider model, and what the
    # placement check fits beside the offsets (built once, where either needs it).
    springs = "offset" in config.passive.terms  # an elastic model: every elastic term needs the offset (passive.py)
    with_springs = None
    if not springs and not problems and (config.check_elastic or placement is not None):
        with_springs = build_problem(
            data, config.passive.with_terms(("offset", "stiffness")), problem.rows, widths, extras
        )
    if config.check_elastic and selection is None and not problems:
        elastic = elastic_check(data, config, problem.rows, fit, widths, extras, with_placement, with_springs)
        if elastic and config.elastic_fallback:
            # The data reject the fixed model: the family the data choose from, its spread in the std, replaces it.
            return _family_result(data, config).with_findings(*elastic, first=True)
        warnings += elastic
        if elastic:
            problems.append(Finding(code=FindingCode.ELASTIC_LACKING))
    placement_check = None
    if placement is not None and not springs and not problems:
        # Whether the data put the markers further off their joint centres than assumed (placement_scale.py): last
        # of the model checks, since free offsets take up what else the model lacks (a spring, a drift, a low-speed
        # friction), which must change the model or the verdict, not only widen the std. So it is not judged where
        # a check found something, nor with an elastic model (on one posture its terms, gravity and the offsets are
        # nearly one: MuJoCo arms with springs and their markers on the centres read as 6-10 mm off); and a spring
        # or drift too small for its own check is fitted beside the offsets (taken up, it read as 10-20 mm).
        assert with_springs is not None  # built above for the same conditions
        skin = np.ones(n + 1, dtype=bool)
        skin[-1] = not data.contact_from_robot
        placement_check = placement_scale(
            problem, placement.columns, placement_sd_m, skin, with_springs, drift_terms()[:2]
        )
        if placement_check.scale > 1.0:
            wider = covariance_from_products(placement_fit, placement.products * placement_check.column_factor)
            fit = dataclasses.replace(fit, covariance=fit.covariance + wider - placement_share)
            placement_share = wider
            if placement_check.note:
                warnings.append(placement_check.note)
    placement_sd = np.sqrt(np.clip(np.diag(placement_share), 0.0, None))
    if config.check_elastic and extras is not None and not problems:
        # Last, with the model checks (live, they run beside the updates): a drift or an elastic term the checks
        # above name is the likelier cause of an off-axis moment.
        perpendicular = [i for i, (key, _) in enumerate(problem.names) if key == "perpendicular_moment_kgm"]
        problems += implausible_perpendicular_moments(
            [problem.names[i][1] for i in perpendicular],
            fit.values[perpendicular],
            extras.prior,
            # A marker off its joint centre, normal to the segment, tilts the segment's angle: an apparent
            # off-axis moment as large as the placement std says, no evidence of a missing moment.
            np.hypot(np.sqrt(np.clip(np.diag(model_spread)[perpendicular], 0.0, None)), placement_sd[perpendicular]),
            family_chosen=config.passive.select,
        )
    sensitivity = passive_offset_sensitivity(problem, fit, n)
    if not problems and not np.isfinite(fit.values).all():
        problems.append(Finding(code=FindingCode.NON_FINITE))
    residual_rms = {joint: float(np.sqrt(np.nanmean(fit.residual[:, j] ** 2))) for j, joint in enumerate(joints)}
    used = problem.rows.sum(axis=0)
    removed = {"wrench_spikes": int(spikes.sum()), "fit_outliers": n_removed}
    diagnostics: dict[str, object] = {
        "hac_lags": fit.lags,
        "max_corr_with_gravity": max_corr_with_gravity,
        "passive_model": config.passive.label,
        "passive_selection": {} if selection is None else selection.to_dict(),
        "passive_curves": curves,
        "elastic_reference": reference.to_dict(),
        "rows_used": {j: int(c) for j, c in zip(joints, used, strict=True)},
        "sensor_noise_nm": {j: float(v) for j, v in zip(joints, noise, strict=True)},
        "misfit_ratio": {j: float(v) for j, v in zip(joints, misfit, strict=True)},
        "removed_samples": {k: v for k, v in removed.items() if v},
        "offset_sensitivity_kgm_per_0_05_nm": sensitivity,
        "friction_transition_rad_s": {j: float(v) for j, v in zip(joints, widths, strict=True)},
        "coulomb_transition_spread_nm": {j: float(v) for j, v in zip(joints, spread, strict=True)},
        "prior_share": shares,
    }
    if placement_check is not None:
        diagnostics["marker_placement"] = placement_check.to_dict(placement_sd_m)
    return IdentificationResult(
        method="joint",
        names=problem.names,
        values=fit.values,
        covariance=fit.covariance,
        findings=(*problems, *warnings),
        summary=f"identified from {data.t_ns.size} samples",
        condition_number=fit.condition,
        residual_rms_nm=residual_rms,
        n_samples=int(data.t_ns.size),
        diagnostics=diagnostics,
        torque_response=TorqueResponse.of(problem, fit),
        held=HeldModel(
            names=problem.names,
            passive=dataclasses.replace(config.passive, select=False),
            widths_rad_s=widths,
            drift=drift is not None,
            placement_sd_m=placement_sd_m if placement_check is None else placement_check.sd_m,
            systematic_covariance=fit.covariance - own_covariance - placement_share,
            curves=basis,
            data_problems=tuple(problems[:data_problems]),
            check_problems=tuple(problems[data_problems:]),
            warnings=tuple(w for w in warnings[data_notes:] if w not in sample_notes),
            diagnostics=diagnostics,
        ),
    )
