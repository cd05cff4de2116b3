"""The test of a term the model lacks: significant, and moving a watched parameter beyond its std."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bsp_ros.core.identification.chi2 import chi2_sf
from bsp_ros.core.identification.result import ParameterName
from bsp_ros.core.identification.stacked import Fit, Problem, augmented, fit_problem, reweighted_values

# An unmodelled term counts when its coefficients differ from 0 at this significance (HAC chi-square) AND
# modelling it moves a static moment or a Coulomb amplitude by more than this many of its std: only then
# would the estimate be wrong beyond its std without it.
MODEL_CHECK_P = 1e-6
MODEL_CHECK_SHIFT_SD = 1.0


def shifts_sd(fit: Fit, wide: Fit, indices: list[int]) -> np.ndarray:
    """How far ``wide`` moves the parameters at ``indices`` from ``fit``, each in std (the larger of the two fits':
    the base fit's is the std the estimate reports, marker placement included)."""
    variance = np.maximum(np.diag(wide.covariance)[indices], np.diag(fit.covariance)[indices])
    return np.asarray(np.abs(wide.values[indices] - fit.values[indices]) / np.sqrt(np.clip(variance, 1e-300, None)))


def shift_bound_sd(fit: Fit, values: np.ndarray, indices: list[int]) -> np.ndarray:
    """What :func:`shifts_sd` can be at most for a wider fit with ``values``, before its covariance is known: the
    shifts in the base fit's std alone (:func:`shifts_sd` divides by the larger of the two)."""
    variance = np.diag(fit.covariance)[indices]
    return np.asarray(np.abs(values[indices] - fit.values[indices]) / np.sqrt(np.clip(variance, 1e-300, None)))


@dataclass(frozen=True)
class TermTest:
    """A term's test: the p-value of its coefficients, the largest shift of a watched parameter in std
    (:func:`shifts_sd`), which one, and the wider fit."""

    p_value: float
    shift_sd: float
    worst: int
    wide: Fit


def term_test(
    problem: Problem,
    fit: Fit,
    extra: np.ndarray,
    names: list[ParameterName],
    watched: list[int],
    can_count: Callable[[np.ndarray], bool] | None = None,
) -> TermTest | None:
    """Fit with the extra columns and test their coefficients; None when the term cannot count.

    The wider fit's values come first: its HAC covariance (most of a fit's cost) is computed only when they could
    make the term count, by ``can_count(values)`` or by default when a watched parameter moves by more than
    :data:`MODEL_CHECK_SHIFT_SD` of the base fit's std (the most any shift in std can be). A term no shift makes
    count is left out either way, so the verdicts are those of testing every term in full.
    """
    wide_problem = augmented(problem, extra, names)
    solved = reweighted_values(wide_problem)
    if can_count is None:
        counts = bool(shift_bound_sd(fit, solved.values, watched).max() > MODEL_CHECK_SHIFT_SD)
    else:
        counts = can_count(solved.values)
    if not counts:
        return None
    wide = fit_problem(wide_problem, solved)
    p = len(problem.names)
    picks = list(range(p, p + len(names)))
    theta = wide.values[picks]
    try:
        statistic = float(theta @ np.linalg.solve(wide.covariance[np.ix_(picks, picks)], theta))
    except np.linalg.LinAlgError:
        return TermTest(1.0, 0.0, watched[0], wide)
    shift = shifts_sd(fit, wide, watched)
    worst = int(np.argmax(shift))
    return TermTest(float(chi2_sf(statistic, len(picks))), float(shift[worst]), watched[worst], wide)
