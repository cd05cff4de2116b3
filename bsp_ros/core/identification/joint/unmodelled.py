"""The test of a term the model lacks: significant, and moving a watched parameter beyond its std."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.chi2 import chi2_sf
from bsp_ros.core.identification.result import ParameterName
from bsp_ros.core.identification.stacked import Fit, Problem, augmented, fit_problem

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


def term_test(
    problem: Problem, fit: Fit, extra: np.ndarray, names: list[ParameterName], watched: list[int]
) -> tuple[float, float, int, Fit]:
    """Fit with the extra columns; return the p-value of their coefficients, the largest shift of a
    ``watched`` parameter in std (:func:`shifts_sd`), which one, and the wider fit."""
    wide = fit_problem(augmented(problem, extra, names))
    p = len(problem.names)
    picks = list(range(p, p + len(names)))
    theta = wide.values[picks]
    try:
        statistic = float(theta @ np.linalg.solve(wide.covariance[np.ix_(picks, picks)], theta))
    except np.linalg.LinAlgError:
        return 1.0, 0.0, watched[0], wide
    shift = shifts_sd(fit, wide, watched)
    worst = int(np.argmax(shift))
    return float(chi2_sf(statistic, len(picks))), float(shift[worst]), watched[worst], wide
