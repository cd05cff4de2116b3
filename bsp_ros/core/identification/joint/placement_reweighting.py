"""How a fit's per-joint weights follow the markers' offsets, and the placement term that follows from it.

The fit weights each joint by its residual variance (:func:`~bsp_ros.core.identification.stacked.reweighted_values`).
Part of what an offset does to the torques no parameter takes up (the handle force's dynamic part on a lever a few
mm off), and where that part is larger than the sensor noise, it lowers the joint's weight: on the paper's sines
four times faster, one 2 mm normal offset at the wrist left a residual of 5 times the sensor noise there and the
wrist's weight fell 30-fold. The estimate then leans less on the joints its own offsets disturb, so the linear
response at the session's weights over-states what offsets of the assumed size do (the forearm's static moment of
a MuJoCo arm: the placement term 1.6-1.8 times the error over 16 sessions). The term is instead the mean, over
offsets drawn from the placement prior, of what the reweighted fit does with each.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from bsp_ros.core.identification.stacked import Problem, Statistics

# Offsets drawn per placement term, from the normal prior with a fixed seed (the same session gives the same std).
# Only the part of the term the reweighting changes comes from them (the linear response at the unperturbed weights
# is exact), so where the weights hardly move the term is the linear one.
PLACEMENT_DRAWS = 512


@dataclass(frozen=True, kw_only=True)
class OffsetStatistics:
    """Per joint ``j`` over its used rows, for ``p`` parameters and ``m`` offset columns (each in units of its sd).

    Attributes
    ----------
    gram : (n, p, p) ``X_j^T X_j``.
    cross : (n, p, m) ``X_j^T D_j``.
    offsets : (n, m, m) ``D_j^T D_j``.
    counts : (n,) the used rows.
    base_variance : (n,) the residual variance once offsets took what they explain (Nm^2): the joint's weight
        were its markers on their centres.
    prior_precision : (p,) the problem's Gaussian priors (1 / sd^2; 0 where none).
    weight_scale : (n,) each joint's weight times its residual variance: 1 where a row is a sample, as identify
        weighs them; the number of samples a row stands for on a plan's coarser grid.
    """

    gram: np.ndarray
    cross: np.ndarray
    offsets: np.ndarray
    counts: np.ndarray
    base_variance: np.ndarray
    prior_precision: np.ndarray
    weight_scale: np.ndarray

    @classmethod
    def of(
        cls, problem: Problem, with_offsets: Statistics, base_variance: np.ndarray, weight_scale: np.ndarray
    ) -> OffsetStatistics:
        """From ``problem``, the per-joint statistics of the problem augmented with the offsets' columns
        (``with_offsets``: its columns then theirs), each joint's residual variance where the offsets took what
        they explain (``base_variance`` (n,), Nm^2; :func:`used_variance` of that fit's residual) and the fit's
        ``weight_scale`` (n,) (its weights times its residual variances)."""
        p = len(problem.names)
        grams = with_offsets[0]
        return cls(
            gram=grams[:, :p, :p],
            cross=grams[:, :p, p:],
            offsets=grams[:, p:, p:],
            counts=problem.rows.sum(axis=0).astype(np.float64),
            base_variance=np.asarray(base_variance, dtype=np.float64),
            prior_precision=np.asarray(problem.prior_precision, dtype=np.float64),
            weight_scale=np.asarray(weight_scale, dtype=np.float64),
        )

    def scaled(self, column_factor: np.ndarray | None) -> OffsetStatistics:
        """The statistics with each offset column multiplied by ``column_factor`` (m,) (None: unchanged)."""
        if column_factor is None:
            return self
        f = np.asarray(column_factor, dtype=np.float64)
        return dataclasses.replace(self, cross=self.cross * f, offsets=self.offsets * np.outer(f, f))


def used_variance(problem: Problem, residual: np.ndarray) -> np.ndarray:
    """(n,) each joint's mean squared ``residual`` (N, n; anything off the used rows), Nm^2, over its used rows."""
    counts = problem.rows.sum(axis=0)
    used = np.where(problem.rows, np.nan_to_num(residual, nan=0.0), 0.0)
    return np.asarray((used**2).sum(axis=0) / np.maximum(counts, 1))


def normal_draws(k: int, m: int) -> np.ndarray:
    """(k, m) draws of ``m`` independent standard normal offsets, seeded."""
    return np.random.default_rng(0).standard_normal((k, m))


def _responses(stats: OffsetStatistics, weights: np.ndarray, draws: np.ndarray) -> np.ndarray:
    """(k, p) each draw's change of the values at its own per-joint weights ``weights`` (k, n), with the priors."""
    design = np.einsum("kj,jpq->kpq", weights, stats.gram) + np.diag(stats.prior_precision)
    moment = np.einsum("kj,jpm,km->kp", weights, stats.cross, draws)
    # Scaled to a unit diagonal: the parameters span decades of units.
    scale = np.sqrt(np.clip(np.einsum("kpp->kp", design), 1e-300, None))
    unit = design / (scale[:, :, None] * scale[:, None, :])
    return np.asarray(np.linalg.solve(unit, (moment / scale)[..., None])[..., 0] / scale)


def _reweighted_responses(stats: OffsetStatistics, draws: np.ndarray) -> np.ndarray:
    """(k, p) each draw's change of the values through the fit's own steps: a solve at unit weights, then twice
    the weights from each joint's residual variance and a solve at them."""
    n = stats.counts.size
    floor = 1e-18 * max(float(stats.base_variance.max()), 1e-300)
    spread = np.einsum("km,jmn,kn->kj", draws, stats.offsets, draws)  # |D_j o|^2
    values = _responses(stats, np.ones((draws.shape[0], n)), draws)
    for _ in range(2):
        # Each joint's residual sum of squares: the base residual's, plus what the offsets leave, |D_j o - X_j d|^2
        # (the cross term with the base residual averages out over the draws).
        left = (
            spread
            - 2.0 * np.einsum("kp,jpm,km->kj", values, stats.cross, draws)
            + np.einsum("kp,jpq,kq->kj", values, stats.gram, values)
        )
        variance = stats.base_variance + np.clip(left, 0.0, None) / np.maximum(stats.counts, 1.0)
        values = _responses(stats, stats.weight_scale / np.maximum(variance, floor), draws)
    return values


def reweighted_placement_covariance(
    stats: OffsetStatistics, column_factor: np.ndarray | None = None, n_draws: int = PLACEMENT_DRAWS
) -> np.ndarray:
    """(p, p) the covariance of the estimate from offsets of unit variance along each column (times
    ``column_factor`` (m,), when given), the fit's per-joint weights following them.

    The linear response ``G`` at the weights of offsets on their centres gives ``G G^T`` exactly; the draws give
    only the difference the reweighting makes, ``E[d d^T] - E[(G o)(G o)^T]`` over the same offsets ``o``.
    """
    stats = stats.scaled(column_factor)
    m = stats.cross.shape[2]
    if m == 0:
        return np.zeros_like(stats.gram[0])
    draws = normal_draws(n_draws, m)
    base_weights = stats.weight_scale / np.maximum(stats.base_variance, 1e-300)
    identity = np.eye(m)
    # G at the unperturbed weights: its columns are the responses to each unit offset.
    linear = _responses(stats, np.broadcast_to(base_weights, (m, base_weights.size)), identity).T  # (p, m)
    reweighted = _reweighted_responses(stats, draws)
    fixed = draws @ linear.T
    exact = linear @ linear.T
    covariance = exact + (reweighted.T @ reweighted - fixed.T @ fixed) / draws.shape[0]
    # The draws' difference may leave a direction slightly negative, which a covariance cannot be: clipped in
    # units of the linear term's std (the parameters span decades of units).
    scale = np.sqrt(np.clip(np.diag(exact), 0.0, None))
    scale[scale == 0] = 1.0
    eigenvalues, vectors = np.linalg.eigh(0.5 * (covariance + covariance.T) / np.outer(scale, scale))
    return np.asarray((vectors * np.clip(eigenvalues, 0.0, None)) @ vectors.T * np.outer(scale, scale))
