"""Model check: an elastic passive moment (offset, stiffness) the fixed model lacks."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.chi2 import chi2_sf
from bsp_ros.core.identification.covariance import correlation_from_covariance
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.unmodelled import MODEL_CHECK_SHIFT_SD
from bsp_ros.core.identification.passive import AUTO
from bsp_ros.core.identification.stacked import (
    Extras,
    Fit,
    Problem,
    build_problem,
    fit_problem,
    problem_names,
    reweighted_values,
)
from bsp_ros.core.streams import joints_for

# The elastic terms count when their coefficients differ from 0 at this significance (HAC chi-square) and they
# move a static moment by more than 0.5 % and MODEL_CHECK_SHIFT_SD of its std.
ELASTIC_P = 1e-4


def _surely_insignificant(values: np.ndarray, covariance: np.ndarray, picks: list[int]) -> bool | None:
    """Whether the terms at ``picks`` are insignificant on ``covariance`` (positive definite there), hence on any
    covariance that adds variance to it (its chi-square can only fall); None where it is singular."""
    sub = covariance[np.ix_(picks, picks)]
    try:
        np.linalg.cholesky(sub)
    except np.linalg.LinAlgError:
        return None
    theta = values[picks]
    return bool(chi2_sf(float(theta @ np.linalg.solve(sub, theta)), len(picks)) >= ELASTIC_P)


def elastic_check(
    data: IdentificationData,
    config: JointConfig,
    rows: np.ndarray,
    base: Fit,
    widths: np.ndarray,
    extras: Extras | None = None,
    covariance_of: Callable[[Problem, Fit], np.ndarray] | None = None,
    wider_problem: Problem | None = None,
) -> list[Finding]:
    """Warn when a linear spring (offset, stiffness) the model lacks is supported by the data and moves the static
    moments: the fixed model would then be valid and wrong (with ``config.elastic_fallback`` the warning says the
    estimate uses the elastic terms the data choose instead). ``covariance_of`` gives the wider fit's covariance
    for the test (the marker placement's share included, as in ``select_passive``: a skin marker off its joint
    centre bends the torques like a spring, and a test on the sensor noise alone finds one in sessions with
    re-placed markers). ``wider_problem``: the samples' problem with the spring's terms, when already built."""
    # A linear spring only. Polynomial terms tested against a model without a spring fit the smallest systematic
    # errors (of the angle filters, on noise-free data) against a gravity torque they can mimic; tested against a
    # fixed spring model, on our own simulator's linear springs with the dynamics, they were "supported" (chi2
    # ~200) and moved the upper arm's static moment by 30 %. Either would throw right estimates away;
    # `--passive auto` weighs them instead, with the spread in the std.
    if "stiffness" in config.passive.terms:
        return []
    wider = config.passive.with_terms(("offset", "stiffness"))
    kinds = " and ".join(term for term in wider.terms if term not in config.passive.terms)
    problem = build_problem(data, wider, rows, widths, extras) if wider_problem is None else wider_problem
    solved = reweighted_values(problem)
    n = data.n_joints
    base_beta, wide_beta = base.values[:n], solved.values[:n]
    change = np.abs(wide_beta - base_beta) / np.maximum(np.abs(base_beta), 1e-9)
    # Against the base fit's std (marker placement included): a shift well inside it cannot make it wrong.
    shift_sd = np.abs(wide_beta - base_beta) / np.sqrt(np.clip(np.diag(base.covariance)[:n], 1e-300, None))
    if not (change.max() > 0.005 and shift_sd.max() > MODEL_CHECK_SHIFT_SD):
        return []  # no significance makes a term count that moves nothing: its covariance is not needed
    fit = fit_problem(problem, solved)
    have = set(problem_names(config.passive, n, extras is not None))
    joint_picks = {
        joint: [i for i, name in enumerate(problem.names) if name[1] == joint and name not in have and i >= n]
        for joint in joints_for(n)
    }
    joint_picks = {joint: picks for joint, picks in joint_picks.items() if picks}
    if covariance_of is not None and all(
        _surely_insignificant(fit.values, fit.covariance, picks) is True for picks in joint_picks.values()
    ):
        return []  # the placement's share only adds variance: insignificant without it, insignificant with it
    covariance = fit.covariance if covariance_of is None else covariance_of(problem, fit)
    notes = []
    correlation = correlation_from_covariance(covariance)
    for joint, picks in joint_picks.items():
        sub = covariance[np.ix_(picks, picks)]
        theta = fit.values[picks]
        statistic = float(theta @ np.linalg.pinv(sub) @ theta)
        if chi2_sf(statistic, len(picks)) < ELASTIC_P:
            worst = int(np.argmax(shift_sd))
            corr = float(np.max(np.abs(correlation[np.ix_(picks, range(n))])))
            values = {
                "kinds": kinds,
                "chi2": statistic,
                "corr": corr,
                "segment": problem.names[worst][1],
                "change_percent": float(100 * change[worst]),
                "shift_sd": float(shift_sd[worst]),
                "fallback": bool(config.elastic_fallback),
                # The `--passive` model that takes the terms up: the estimate's own with the fallback, else to try.
                "passive_option": AUTO,
            }
            notes.append(Finding(code=FindingCode.ELASTIC_TERM, where=joint, values=values))
    return notes
