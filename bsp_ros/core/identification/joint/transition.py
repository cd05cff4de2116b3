"""Model check and fix: a smooth Coulomb transition, tanh(v / w), instead of a sign step."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.stacked import Fit, Problem, candidate_products, normal_equations

# Candidate widths of a smooth friction transition, tanh(v / w) (rad/s): 0.25 to 16 mrad/s.
TRANSITION_WIDTHS_RAD_S = 0.00025 * 2.0 ** (np.arange(25) / 4.0)
# A smooth transition is detected when it lowers the weighted residual sum of squares by this much (a
# chi-square-like figure, inflated by autocorrelation): clean sessions give at most ~1, sessions with 5%
# marker dropouts (noisy directions at each run's ends) up to ~200 rarely, a 1 mrad/s transition over
# 60 s 110 at the wrist and 1200 at the elbow.
TRANSITION_MIN_GAIN = 100.0


def transition_widths(
    problem: Problem, fit: Fit, data: IdentificationData, config: JointConfig
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Width of a smooth Coulomb transition at each joint, and how uncertain that leaves the amplitude.

    A profile over :data:`TRANSITION_WIDTHS_RAD_S` (and the sign step, width 0), one joint at a time, on
    the weighted normal equations: swapping one column costs O(N), not a new fit.

    Returns
    -------
    widths : (n,) rad/s; 0 where a sign step fits as well (gain below :data:`TRANSITION_MIN_GAIN`).
    spread : (n,) half the range (Nm) of the Coulomb amplitudes over the widths the data cannot tell from
        the chosen one (residual within :data:`TRANSITION_MIN_GAIN` of it): a model uncertainty the
        covariance of one fit does not hold.
    span : (n,) the full range (Nm) of the Coulomb amplitudes from the sign step to the chosen width: what a
        joint that hardly leaves its transition leaves open (the data then cannot say how wide it is).
    """
    n = data.n_joints
    widths, spread, span = np.zeros(n), np.zeros(n), np.zeros(n)
    if "coulomb" not in config.passive.terms:
        return widths, spread, span
    w = np.where(problem.rows, fit.weights[None, :], 0.0)
    design, moment, total = normal_equations(problem, fit.weights)

    def solve(a: np.ndarray, b: np.ndarray) -> tuple[float, np.ndarray]:
        try:
            x = np.linalg.solve(a, b)
        except np.linalg.LinAlgError:
            return np.inf, np.full(b.size, np.nan)
        return total - float(b @ x), x

    base, base_x = solve(design, moment)
    for j in range(n):
        column = config.passive.local_column("coulomb", n, j)
        used = problem.rows[:, j, None]  # the fit's weights are positive: its weighted rows
        (x_j, y_j), w_j = problem.joint_rows(j), w[:, j]  # 0 off the used rows
        # Every candidate width's column at once (N, widths), 0 off the used rows.
        c = np.where(used, np.tanh(data.velocity_rad_s[:, j, None] / TRANSITION_WIDTHS_RAD_S[None, :]), 0.0)
        crosses, squares, targets = candidate_products(x_j, w_j, y_j, c)
        # Each candidate's normal equations: the Coulomb row and column swapped for the candidate's.
        crosses[column] = squares
        a = np.repeat(design[None], crosses.shape[1], axis=0)
        b = np.repeat(moment[None], crosses.shape[1], axis=0)
        a[:, column, :], a[:, :, column], b[:, column] = crosses.T, crosses.T, targets
        try:
            solved = [(total - float(b[m] @ x), x) for m, x in enumerate(np.linalg.solve(a, b[..., None])[..., 0])]
        except np.linalg.LinAlgError:  # one candidate singular: solve them one by one
            solved = [solve(a[m], b[m]) for m in range(a.shape[0])]
        profile = [(base, 0.0, float(base_x[column]))]
        profile += [
            (v, float(width), float(x[column])) for (v, x), width in zip(solved, TRANSITION_WIDTHS_RAD_S, strict=True)
        ]
        best = min(profile)
        chosen = best if base - best[0] > TRANSITION_MIN_GAIN else profile[0]
        widths[j] = chosen[1]
        near = [c for value, _, c in profile if value <= chosen[0] + TRANSITION_MIN_GAIN and np.isfinite(c)]
        spread[j] = 0.5 * (max(near) - min(near)) if near else 0.0
        narrower = [c for _, width, c in profile if width <= chosen[1] and np.isfinite(c)]
        span[j] = max(narrower) - min(narrower) if narrower else 0.0
    return widths, spread, span
