"""The stacked identification's verdict on its fit: does the model fit the data, and what does each parameter's
estimate say (confounded with gravity, at its bound, uncertain)."""

from __future__ import annotations

import dataclasses

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.covariance import correlation_from_covariance
from bsp_ros.core.identification.elastic import ElasticReference
from bsp_ros.core.identification.joint.curves import curve_basis
from bsp_ros.core.identification.joint.fallback import elastic_family_fit
from bsp_ros.core.identification.joint.misfit import misfit_against_noise
from bsp_ros.core.identification.joint.outliers import MIN_OUTLIER_NM
from bsp_ros.core.identification.joint.stage import Outcome, Stage
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.identification.stacked import Problem, reweighted_values
from bsp_ros.core.streams import joints_for

__all__ = [
    "UNIDENTIFIABLE_CONDITION",
    "judge_fit",
    "judge_parameters",
    "static_moments_at_bound",
    "unbounded_static_moments",
    "unidentifiable_problem",
]

# Above this column-scaled condition number no std is meaningful: parameters the motion cannot tell apart.
UNIDENTIFIABLE_CONDITION = 1e8


def unidentifiable_problem(condition: float) -> Finding:
    """The problem of a fit whose column-scaled condition number is above :data:`UNIDENTIFIABLE_CONDITION`."""
    return Finding(code=FindingCode.NOT_IDENTIFIABLE, values={"condition": float(condition)})


def unbounded_static_moments(problem: Problem) -> np.ndarray:
    """(p,) the fit of ``problem`` with the static moments' lower bound 0 lifted: the data's own estimate."""
    n = problem.torque.shape[1]
    lower = np.where(np.arange(len(problem.names)) < n, -np.inf, problem.lower)
    return reweighted_values(dataclasses.replace(problem, lower=lower)).values


def static_moments_at_bound(stage: Stage) -> np.ndarray:
    """(n,) whether the fit holds each static moment at its lower bound."""
    lower = stage.problem.lower[: stage.n]
    return np.asarray(np.isfinite(lower) & (stage.fit.values[: stage.n] <= lower + 1e-12))


def judge_fit(stage: Stage) -> Stage | IdentificationResult:
    """The passive curves, and whether the model fits: a joint whose residual is far above the sensor noise the
    data show does not fit (where nothing else is wrong, the elastic family the data choose is tried instead), and
    a fit whose condition number is too large cannot be trusted."""
    data, config, fit = stage.data, stage.config, stage.fit
    reference = ElasticReference.from_angles(data.passive_q_rad)
    basis = curve_basis(data, reference, fit, stage.probed)
    noise, misfit = misfit_against_noise(fit, stage.judged_residual)
    misfits = tuple(
        Finding(
            code=FindingCode.MODEL_MISFIT,
            where=joint,
            values={"rms_nm": float(misfit[j] * noise[j]), "ratio": float(misfit[j]), "noise_nm": float(noise[j])},
        )
        for j, joint in enumerate(joints_for(stage.n))
        if misfit[j] > config.max_misfit and misfit[j] * noise[j] > MIN_OUTLIER_NM
    )
    if misfits and not stage.problems and config.elastic_fallback and config.check_elastic and stage.selection is None:
        family = elastic_family_fit(stage.given, config, list(misfits))
        if family is not None:
            return family
    problems, notes = list(misfits), []
    if fit.condition > UNIDENTIFIABLE_CONDITION:
        problems.append(unidentifiable_problem(fit.condition))
    elif fit.condition > config.max_condition:
        # An honest std is large here, not wrong: the estimate stays, its std says what the motion leaves open.
        values = {"condition": float(fit.condition), "max_condition": config.max_condition}
        notes.append(Finding(code=FindingCode.POORLY_EXCITED, values=values))
    stage = dataclasses.replace(
        stage,
        curves=basis,
        passive_curves={} if basis is None else basis.curves(fit),
        elastic_reference=reference,
        noise_nm=noise,
        misfit=misfit,
    )
    return stage.apply(Outcome(problems=tuple(problems), notes=tuple(notes)))


def _confounded(stage: Stage, i: int, correlation: np.ndarray, std: np.ndarray) -> Finding | None:
    """Whether passive parameter ``i`` is so correlated with a static moment that the latter is uncertain."""
    n, fit, (key, owner) = stage.n, stage.fit, stage.problem.names[i]
    partner = int(np.argmax(np.abs(correlation[i, :n])))
    corr = float(abs(correlation[i, partner]))
    value = fit.values[partner]
    rel_std = std[partner] / value if value > 0 else np.inf
    if corr > stage.config.confounded_corr and rel_std > stage.config.confounded_rel_std:
        segment = stage.problem.names[partner][1]
        values = {"key": key, "corr": corr, "segment": segment, "rel_std": float(rel_std)}
        return Finding(code=FindingCode.CONFOUNDED, where=owner, values=values)
    return None


def _at_bound(stage: Stage, i: int, std: float, unbounded: np.ndarray | None) -> tuple[Finding | None, bool]:
    """A parameter at its lower bound: a static moment the data put below 0 (a problem), or one or a passive term
    the motion leaves open there (a note); and whether it is a problem."""
    problem, fit, n = stage.problem, stage.fit, stage.n
    key, owner = problem.names[i]
    if not (np.isfinite(problem.lower[i]) and fit.values[i] <= problem.lower[i] + 1e-12):
        return None, False
    if i < n:
        assert unbounded is not None
        own = unbounded[i]
        if own + 3.0 * std < 0.0:
            return Finding(code=FindingCode.STATIC_MOMENT_AT_BOUND, where=owner), True
        # The data's own (unbounded) estimate lies within 3 std of 0: the motion leaves this static moment open (one
        # posture, the elastic family), which its std says; no evidence of a fault.
        return Finding(code=FindingCode.STATIC_MOMENT_OPEN, where=owner, values={"own_kgm": float(own)}), False
    if std > 0:
        values = {"key": key, "lower": float(problem.lower[i])}
        return Finding(code=FindingCode.PARAMETER_AT_BOUND, where=owner, values=values), False
    return None, False


def judge_parameters(stage: Stage) -> Stage:
    """Each parameter's estimate: passive terms confounded with gravity, parameters at their bounds, static moments
    whose std is over half their value."""
    fit, n = stage.fit, stage.n
    correlation = correlation_from_covariance(fit.covariance)
    std = np.sqrt(np.clip(np.diag(fit.covariance), 0.0, None))
    names = stage.problem.names[: stage.problem.passive_end]
    unbounded = unbounded_static_moments(stage.problem) if static_moments_at_bound(stage).any() else None
    problems: list[Finding] = []
    notes: list[Finding] = []
    correlated: dict[str, float] = {}
    for i, (key, owner) in enumerate(names):
        if i >= n:
            correlated[f"{key}/{owner}"] = float(np.max(np.abs(correlation[i, :n])))
            confounded = _confounded(stage, i, correlation, std)
            if confounded is not None:
                notes.append(confounded)
        bound, invalid = _at_bound(stage, i, float(std[i]), unbounded)
        if bound is not None:
            (problems if invalid else notes).append(bound)
        if i < n and fit.values[i] > 0 and std[i] > 0.5 * fit.values[i]:
            values = {"value_kgm": float(fit.values[i]), "std_kgm": float(std[i])}
            notes.append(Finding(code=FindingCode.UNCERTAIN_STATIC_MOMENT, where=owner, values=values))
    stage = dataclasses.replace(stage, max_corr_with_gravity=correlated)
    return stage.apply(Outcome(problems=tuple(problems), notes=tuple(notes)))
