"""How a fit's per-joint weights follow the markers' offsets, and the placement term that follows from it.

The fit weights each joint by its residual variance (:func:`~bsp_ros.core.identification.stacked.reweighted_values`).
Part of what an offset does to the torques no parameter takes up (the handle force's dynamic part on a lever a few
mm off), and where that part is larger than the sensor noise, it lowers the joint's weight: on the paper's sines
four times faster, one 2 mm normal offset at the wrist left a residual of 5 times the sensor noise there and the
wrist's weight fell 30-fold. The estimate then leans less on the joints its own offsets disturb, and how much
depends on the offsets: the linear response at the session's weights, applied to offsets of the assumed size in
every direction, over-states the error of most sessions (the forearm's static moment of a MuJoCo arm: the term
1.6-1.8 times the error over 16 sessions), and the linear response at the weights of centred markers misses the
session whose one large offset took a joint's weight away (a perpendicular moment 4 std off). The term is the mean,
over offsets drawn from the placement prior, of what the reweighted fit does with each; per parameter the mean
over the draws whose per-joint residual variances match the session's own where that is clearly larger.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from bsp_ros.core.identification.stacked import Problem, Statistics

# Offsets drawn per placement term, from the normal prior with a fixed seed (the same session gives the same std).
PLACEMENT_DRAWS = 2048
# A draw's weight: a Gaussian in the log of its per-joint residual variances over the session's, of this width
# first, widened (doubled) until the weighted draws count at least MIN_DRAWS_CONDITIONAL (their effective number);
# without a match that wide, every draw weighs the same.
VARIANCE_MATCH_LOG = (0.25, 0.5, 1.0, 2.0)
MIN_DRAWS_CONDITIONAL = 64.0
# A parameter's std takes the matched draws' where it is more than this many times the prior mean's: a session
# whose residuals show a weight taken away (one 2.6 sd offset at the wrist: a perpendicular moment's 2.2 times),
# not the ordinary scatter of a few draws about it (which, taken whenever larger, widened the hand's std by 20 %).
MATCHED_WIDER = 1.5


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
    observed_variance : (n,) the session's own per-joint residual variances (Nm^2), which its offsets raised:
        where the draws that match them give a clearly larger term, it is theirs; None (a plan's expected session):
        the prior's mean alone.
    """

    gram: np.ndarray
    cross: np.ndarray
    offsets: np.ndarray
    counts: np.ndarray
    base_variance: np.ndarray
    prior_precision: np.ndarray
    weight_scale: np.ndarray
    observed_variance: np.ndarray | None = None

    @classmethod
    def of(
        cls,
        problem: Problem,
        with_offsets: Statistics,
        base_variance: np.ndarray,
        weight_scale: np.ndarray,
        observed_variance: np.ndarray | None = None,
    ) -> OffsetStatistics:
        """From ``problem``, the per-joint statistics of the problem augmented with the offsets' columns
        (``with_offsets``: its columns then theirs), each joint's residual variance where the offsets took what
        they explain (``base_variance`` (n,), Nm^2; :func:`used_variance` of that fit's residual) and the fit's
        ``weight_scale`` (n,) (its weights times its residual variances), and its ``observed_variance``."""
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
            observed_variance=None if observed_variance is None else np.asarray(observed_variance, dtype=np.float64),
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


def _scores(stats: OffsetStatistics, draws: np.ndarray) -> np.ndarray:
    """(n, k, p) per joint each draw's ``X_j^T D_j o``."""
    return np.asarray(np.matmul(draws[None, :, :], np.swapaxes(stats.cross, 1, 2)))


def _responses(stats: OffsetStatistics, weights: np.ndarray, scores: np.ndarray) -> np.ndarray:
    """(k, p) each draw's change of the values at its own per-joint weights ``weights`` (k, n), with the priors,
    from its per-joint scores ``scores`` (n, k, p)."""
    n, p = stats.gram.shape[:2]
    design = (weights @ stats.gram.reshape(n, p * p)).reshape(-1, p, p) + np.diag(stats.prior_precision)
    moment = np.einsum("kj,jkp->kp", weights, scores)
    # Scaled to a unit diagonal: the parameters span decades of units.
    diagonal = np.einsum("kpp->kp", design)
    scale = np.sqrt(np.where(diagonal > 0.0, diagonal, 1.0))
    unit = design / (scale[:, :, None] * scale[:, None, :])
    rhs = (moment / scale)[..., None]
    try:
        solved = np.linalg.solve(unit, rhs)
    except np.linalg.LinAlgError:
        # A design no prior holds in some direction (a session too short for its model, which the checks call
        # not identifiable): the least-squares response, which is 0 along that direction.
        solved = np.linalg.pinv(unit, hermitian=True) @ rhs
    return np.asarray(solved[..., 0] / scale)


def _reweighted_responses(stats: OffsetStatistics, draws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(k, p) each draw's change of the values through the fit's own steps (a solve at unit weights, then twice
    the weights from each joint's residual variance and a solve at them), and (k, n) the residual variances of the
    last weights."""
    k, n = draws.shape[0], stats.counts.size
    floor = 1e-18 * max(float(stats.base_variance.max()), 1e-300)
    scores = _scores(stats, draws)
    spread = np.stack([np.sum((draws @ stats.offsets[j]) * draws, axis=1) for j in range(n)], axis=1)  # |D_j o|^2
    values = _responses(stats, np.ones((k, n)), scores)
    for _ in range(2):
        # Each joint's residual sum of squares: the base residual's, plus what the offsets leave, |D_j o - X_j d|^2
        # (the cross term with the base residual averages out over the draws).
        left = np.stack(
            [
                spread[:, j]
                - 2.0 * np.sum(values * scores[j], axis=1)
                + np.sum((values @ stats.gram[j]) * values, axis=1)
                for j in range(n)
            ],
            axis=1,
        )
        variance = stats.base_variance + np.clip(left, 0.0, None) / np.maximum(stats.counts, 1.0)
        values = _responses(stats, stats.weight_scale / np.maximum(variance, floor), scores)
    return values, variance


def match_weights(variance: np.ndarray, observed: np.ndarray) -> np.ndarray:
    """(k,) each draw's weight (summing to 1) by how its per-joint residual variances ``variance`` (k, n) match
    the session's ``observed`` (n,), Nm^2: see :data:`VARIANCE_MATCH_LOG`."""
    distance = np.sum((np.log(np.maximum(variance, 1e-300)) - np.log(np.maximum(observed, 1e-300))) ** 2, axis=1)
    for width in VARIANCE_MATCH_LOG:
        log_weight = -0.5 * distance / width**2
        weight = np.exp(log_weight - log_weight.max())
        weight /= weight.sum()
        if 1.0 / float(np.sum(weight**2)) >= MIN_DRAWS_CONDITIONAL:
            return weight
    return np.full(variance.shape[0], 1.0 / variance.shape[0])


def reweighted_placement_covariance(
    stats: OffsetStatistics, column_factor: np.ndarray | None = None, n_draws: int = PLACEMENT_DRAWS
) -> np.ndarray:
    """(p, p) the covariance of the estimate from offsets of unit variance along each column (times
    ``column_factor`` (m,), when given), the fit's per-joint weights following them.

    The prior's mean: the linear response ``G`` at the weights of offsets on their centres gives ``G G^T`` exactly,
    and the draws give only the difference the reweighting makes, ``E[d d^T] - E[(G o)(G o)^T]`` over the same
    offsets ``o``. Where ``stats`` holds the session's residual variances, a parameter whose std over the draws
    that match them (:func:`match_weights`) is more than :data:`MATCHED_WIDER` times that takes it: a session whose
    residuals show that its offsets took a joint's weight away is not held to what a typical session's offsets do.
    """
    stats = stats.scaled(column_factor)
    m = stats.cross.shape[2]
    if m == 0:
        return np.zeros_like(stats.gram[0])
    draws = normal_draws(n_draws, m)
    reweighted, variance = _reweighted_responses(stats, draws)
    base_weights = stats.weight_scale / np.maximum(stats.base_variance, 1e-300)
    identity = np.eye(m)
    # G at the unperturbed weights: its columns are the responses to each unit offset.
    linear = _responses(stats, np.broadcast_to(base_weights, (m, base_weights.size)), _scores(stats, identity)).T
    fixed = draws @ linear.T
    exact = linear @ linear.T
    covariance = exact + (reweighted.T @ reweighted - fixed.T @ fixed) / draws.shape[0]
    # The draws' difference may leave a direction slightly negative, which a covariance cannot be: clipped in
    # units of the linear term's std (the parameters span decades of units).
    scale = np.sqrt(np.clip(np.diag(exact), 0.0, None))
    scale[scale == 0] = 1.0
    eigenvalues, vectors = np.linalg.eigh(0.5 * (covariance + covariance.T) / np.outer(scale, scale))
    covariance = (vectors * np.clip(eigenvalues, 0.0, None)) @ vectors.T * np.outer(scale, scale)
    if stats.observed_variance is None:
        return np.asarray(covariance)
    weight = match_weights(variance, stats.observed_variance)
    matched = np.einsum("k,kp->p", weight, reweighted**2)
    prior = np.diag(covariance)
    widen = np.sqrt(np.divide(matched, prior, out=np.ones_like(prior), where=prior > 0))
    widen = np.where(widen > MATCHED_WIDER, widen, 1.0)
    return np.asarray(covariance * np.outer(widen, widen))
