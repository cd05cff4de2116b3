"""The stacked least-squares problem of all joints: its columns, priors, weighted bounded fit and HAC covariance."""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from bsp_ros.core.identification.covariance import design_inverse, hac_covariance
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.elastic import (
    ElasticReference,
    elastic_columns,
    elastic_names,
    elastic_prior_precision,
)
from bsp_ros.core.identification.passive import TERMS, PassiveModel
from bsp_ros.core.identification.priors import BasePrior
from bsp_ros.core.identification.result import ParameterName
from bsp_ros.core.model import GRAVITY_M_S2, absolute_angles_rad
from bsp_ros.core.streams import joints_for, segments_for

# Per joint: X^T X (n, p, p), X^T y (n, p), y^T y (n,).
Statistics = tuple[np.ndarray, np.ndarray, np.ndarray]


class JointRegressors:
    """A :class:`Problem`'s regressor per joint (N, p): its column blocks joined when a pass first needs them,
    and kept (a problem of one block holds them joined already). The problem's cache; the problem itself is
    never changed."""

    def __init__(self, blocks: tuple[tuple[np.ndarray, ...], ...]) -> None:
        self._blocks = blocks
        self._joined: dict[int, np.ndarray] = {}

    def joined(self, joint: int) -> bool:
        """Whether ``joint``'s regressor is at hand without joining its blocks."""
        return len(self._blocks) == 1 or joint in self._joined

    def __getitem__(self, joint: int) -> np.ndarray:
        if len(self._blocks) == 1:
            return self._blocks[0][joint]
        if joint not in self._joined:
            self._joined[joint] = np.hstack([block[joint] for block in self._blocks])
        return self._joined[joint]


@dataclass(frozen=True, kw_only=True)
class Problem:
    """The joint model stacked over samples and joints: ``torque[t, i] = sum_k X_i[t, k] theta_k`` on joint ``i``'s
    used rows, with bounds and Gaussian priors on some parameters (``p`` of them, ``n`` joints, ``N`` samples).

    Immutable: what is computed from its arrays once and kept (each joint's joined regressor, the statistics)
    lives in cached properties, never written into the instance by hand."""

    names: list[ParameterName]
    # The regressor's column blocks, in order, each as one (N, p_k) array per joint ``i`` whose rows the joint does
    # not use are 0: every pass runs over one joint's contiguous rows (the stacked (N, n, p) array's are strided),
    # none gathers them, and a row of zeros adds nothing to a sum. A problem augmented with a few columns keeps its
    # base's arrays and the new columns apart, and joins them per joint (``joint_rows``) only when a pass over
    # them needs it (a model check that looks at a wider fit's values alone solves from the statistics).
    blocks: tuple[tuple[np.ndarray, ...], ...]
    torque: np.ndarray  # (N, n)
    rows: np.ndarray  # (N, n) bool: row used
    lower: np.ndarray
    upper: np.ndarray
    prior_mean: np.ndarray  # (p,) Gaussian prior means (0 where none)
    prior_precision: np.ndarray  # (p,) 1 / sd^2 of the priors (0 where none)
    passive_end: int  # parameters [n, passive_end) are the passive terms
    # (N,) per joint: its torques, 0 off its used rows (an augmented problem shares its base's).
    joint_torques: tuple[np.ndarray, ...] = field(compare=False, repr=False)
    # The per-joint statistics when known at construction (an augmented problem's, from its base's); else
    # ``statistics`` computes them on first use. The arrays above are never changed after construction.
    known_statistics: Statistics | None = field(default=None, compare=False, repr=False)

    @cached_property
    def statistics(self) -> Statistics:
        """Per joint ``j`` over its used rows: ``X_j^T X_j`` (n, p, p), ``X_j^T y_j`` (n, p) and ``y_j^T y_j``
        (n,), computed once: every reweighting, check and augmented problem solves from them."""
        if self.known_statistics is not None:
            return self.known_statistics
        n, p = self.torque.shape[1], len(self.names)
        grams, moments, totals = np.empty((n, p, p)), np.empty((n, p)), np.empty(n)
        for j in range(n):
            x, y = self.joint_rows(j)
            grams[j], moments[j], totals[j] = x.T @ x, x.T @ y, y @ y
        return grams, moments, totals

    @cached_property
    def regressors(self) -> JointRegressors:
        """Each joint's regressor, its blocks joined once when first needed."""
        return JointRegressors(self.blocks)

    def joint_rows(self, joint: int) -> tuple[np.ndarray, np.ndarray]:
        """``joint``'s regressor (N, p) and torques (N,), both 0 off its used rows, the blocks joined once and
        kept: the statistics, the augmented problems of the model checks and their candidate profiles use them."""
        return self.regressors[joint], self.joint_torques[joint]

    def joint_torque(self, joint: int) -> np.ndarray:
        """(N,) ``joint``'s torques, 0 off its used rows."""
        return self.joint_torques[joint]

    def joint_blocks(self, joint: int) -> list[tuple[slice, np.ndarray]]:
        """``joint``'s column blocks (N, p_k), each with the slice of the parameters it holds: for the passes that
        need not join them."""
        out, start = [], 0
        for block in self.blocks:
            out.append((slice(start, start + block[joint].shape[1]), block[joint]))
            start += block[joint].shape[1]
        return out

    def residual(self, values: np.ndarray) -> np.ndarray:
        """(N, n) the torques less the model's at ``values`` on the used rows, 0 elsewhere (block by block: an
        augmented problem's columns are not joined for it)."""
        out = np.empty(self.torque.shape)
        for j in range(self.torque.shape[1]):
            if self.regressors.joined(j):
                predicted = self.regressors[j] @ values
            else:
                predicted = sum(x @ values[cols] for cols, x in self.joint_blocks(j))
            out[:, j] = self.joint_torques[j] - predicted
        return out


def used_torques(torque: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, ...]:
    """(N,) per joint: its torques (``torque`` (N, n)), 0 off its used rows (``rows`` (N, n))."""
    return tuple(np.where(rows[:, j], torque[:, j], 0.0) for j in range(torque.shape[1]))


@dataclass(frozen=True)
class Extras:
    """The base-parameter blocks beyond gravity: dynamics of the static moments, perpendicular moments and
    grouped inertias, with their priors."""

    base: np.ndarray  # (N, n, 3n) base regressor [beta, gamma, zeta]
    prior: BasePrior


@dataclass(frozen=True, kw_only=True)
class Fit:
    """A solved :class:`Problem`: values (p,), HAC covariance (p, p), the residuals and per-joint noise, the
    condition number of the scaled design and the HAC's lags."""

    values: np.ndarray
    covariance: np.ndarray
    residual: np.ndarray  # (N, n), NaN off the used rows
    sigma: np.ndarray  # (n,)
    condition: float
    lags: int
    design: np.ndarray  # (p, p) X^T W X over the used rows
    weights: np.ndarray  # (n,) per-joint weights 1 / sigma^2


def build_problem(
    data: IdentificationData,
    passive: PassiveModel,
    rows: np.ndarray,
    widths: np.ndarray | None = None,
    extras: Extras | None = None,
) -> Problem:
    """The stacked problem; ``widths`` (n,) rad/s > 0 replace a joint's Coulomb ``sign(v)`` by ``tanh(v / w)``.

    Columns: the static moments, the local passive terms joint by joint, the elastic terms beyond a linear spring
    (centred on the session's range, :class:`ElasticReference`), then (with ``extras``) the perpendicular
    moments and the grouped inertias, each of the latter with its Gaussian prior.
    """
    n = data.n_joints
    local = passive.local
    k = len(local)
    names = problem_names(passive, n, extras is not None)
    dynamics = 0 if extras is None else 2 * n
    # Joint i's gravity columns are g cos(phi_j) for the segments j >= i it carries (gravity_regressor's row i).
    gravity = GRAVITY_M_S2 * np.cos(absolute_angles_rad(data.q_rad))
    passive_q = data.passive_q_rad  # the trunk's tilt turns gravity, not the passive moments
    elastic = None
    if passive.elastic:
        elastic = elastic_columns(passive_q, passive.elastic, ElasticReference.from_angles(passive_q))
    p = n + n * k + (0 if elastic is None else elastic.shape[2])
    columns = []
    for j in range(n):
        x = np.zeros((data.t_ns.size, p + dynamics))
        if extras is not None:
            x[:, :n], x[:, p:] = extras.base[:, j, :n], extras.base[:, j, n:]
        else:
            x[:, j:n] = gravity[:, j:]
        x[:, n + j * k : n + (j + 1) * k] = passive.columns(passive_q, data.velocity_rad_s, j)
        if widths is not None and widths[j] > 0 and "coulomb" in local:
            x[:, n + j * k + local.index("coulomb")] = np.tanh(data.velocity_rad_s[:, j] / widths[j])
        if elastic is not None:
            x[:, n + n * k : p] = elastic[:, j, :]
        x[~rows[:, j]] = 0.0
        columns.append(x)
    lower = [0.0] * n + [TERMS[term][2] for _ in range(n) for term in local] + [-np.inf] * (p - n - n * k)
    precision = elastic_prior_precision(names[:p])
    mean = np.zeros(p)
    if extras is not None:
        prior = extras.prior
        mean = np.concatenate((mean, prior.perpendicular_mean_kgm, prior.inertia_mean_kgm2))
        sd = np.concatenate((prior.perpendicular_sd_kgm, prior.inertia_sd_kgm2))
        precision = np.concatenate((precision, np.where(sd > 0, 1.0 / np.maximum(sd, 1e-300) ** 2, 0.0)))
        lower += [-np.inf] * dynamics
    return Problem(
        names=names,
        blocks=(tuple(columns),),
        torque=data.tau_nm,
        rows=rows,
        lower=np.array(lower),
        upper=np.full(p + dynamics, np.inf),
        prior_mean=mean,
        prior_precision=precision,
        passive_end=p,
        joint_torques=used_torques(data.tau_nm, rows),
    )


def problem_names(passive: PassiveModel, n: int, dynamics: bool) -> list[ParameterName]:
    """The parameter names of :func:`build_problem`'s columns, in order, for an ``n``-joint chain."""
    joints, segments = joints_for(n), segments_for(n)
    names: list[ParameterName] = [("static_moment_kgm", s) for s in segments]
    names += [(TERMS[term][0], joint) for joint in joints for term in passive.local]
    names += elastic_names(passive.elastic, n)
    if dynamics:
        names += [("perpendicular_moment_kgm", s) for s in segments] + [("grouped_inertia_kgm2", s) for s in segments]
    return names


def triangular(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``R, c`` with ``|a x - b|^2 = |R x - c|^2 + const``: the bounded problem at p x p cost.

    Normal equations with Cholesky are fast for tall, column-scaled, well-conditioned ``a``; QR otherwise.
    """
    gram = a.T @ a
    try:
        lower = np.linalg.cholesky(gram)
        if np.linalg.cond(lower) < 1e6:
            return lower.T, np.linalg.solve(lower, a.T @ b)
    except np.linalg.LinAlgError:
        pass
    q_factor, r_factor = np.linalg.qr(a, mode="reduced")
    return r_factor, q_factor.T @ b


def prior_rows(problem: Problem) -> tuple[np.ndarray, np.ndarray]:
    """Pseudo-observations ``sqrt(P) (theta - theta_0)`` of the Gaussian priors: rows (m, p) and targets (m,)."""
    picks = np.flatnonzero(problem.prior_precision > 0)
    root = np.sqrt(problem.prior_precision[picks])
    rows = np.zeros((picks.size, len(problem.names)))
    rows[np.arange(picks.size), picks] = root
    return rows, root * problem.prior_mean[picks]


def joint_products(problem: Problem, weights: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``sum_i X_i^T w_i b[:, i]`` over each joint's used rows: (p, m) for ``b`` (N, n, m), (p,) for ``b`` (N, n).
    One BLAS product per joint and block.

    Parameters
    ----------
    problem : whose columns ``X_i`` (0 off joint ``i``'s used rows).
    weights : (n,) per-joint weights (1 / sigma^2).
    b : (N, n, m) or (N, n), finite.
    """
    total = np.zeros((len(problem.names), *b.shape[2:]))
    for i in range(problem.torque.shape[1]):
        weighted = weights[i] * b[:, i]
        for cols, x in problem.joint_blocks(i):
            total[cols] += x.T @ weighted
    return total


def candidate_products(
    regressor_j: np.ndarray, weights_j: np.ndarray, torque_j: np.ndarray, candidates: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What a profile over candidate columns of one joint needs of each to border or swap into the normal
    equations: ``X^T W c`` (p, m), ``c^T W c`` (m,) and ``y^T W c`` (m,), every candidate in one BLAS product.

    Parameters
    ----------
    regressor_j : (N, p) the joint's columns; weights_j, torque_j : (N,) the rows' weights and torques (0 off its
        used rows).
    candidates : (N, m) one column per candidate, finite.
    """
    weighted = weights_j[:, None] * candidates
    return regressor_j.T @ weighted, (weighted * candidates).sum(axis=0), torque_j @ weighted


def joint_scores(problem: Problem, weighted_residual: np.ndarray, columns: np.ndarray | None = None) -> np.ndarray:
    """(N, m) per-sample scores ``sum_i x_ti r_ti`` summed over the joints of each sample (0 where no joint uses
    the sample), of the columns ``X_i`` or, given ``columns`` (p, m), of the projected rows ``X_i columns``.

    Parameters
    ----------
    problem : whose columns (0 off each joint's used rows).
    weighted_residual : (N, n) the weighted residual, finite (what lies off the used rows meets 0 columns).
    columns : (p, m) a projection of the parameters, or None for all p of them.
    """
    count = weighted_residual.shape[0]
    out = np.zeros((count, len(problem.names) if columns is None else columns.shape[1]))
    for i in range(weighted_residual.shape[1]):
        r = weighted_residual[:, i, None]
        for cols, x in problem.joint_blocks(i):  # block by block: an augmented problem's columns are never joined
            if columns is None:
                out[:, cols] += x * r
            else:
                out += (x @ columns[cols]) * r
    return out


def joint_statistics(problem: Problem) -> Statistics:
    """Per joint ``j`` over its used rows: ``X_j^T X_j`` (n, p, p), ``X_j^T y_j`` (n, p) and ``y_j^T y_j`` (n,).

    The weights of the fit are per joint, so these give the normal equations of every reweighting at p x p
    cost (one pass over the samples, BLAS products). Computed once per problem (:attr:`Problem.statistics`)."""
    return problem.statistics


def _augmented_statistics(problem: Problem, extra: tuple[np.ndarray, ...]) -> Statistics:
    """:func:`joint_statistics` of ``problem`` with the columns ``extra`` (per joint (N, m), 0 off its used rows)
    appended, from its own: only the products with the new columns pass over the samples."""
    grams, moments, totals = joint_statistics(problem)
    n, p, m = grams.shape[0], grams.shape[1], extra[0].shape[1]
    out_grams, out_moments = np.empty((n, p + m, p + m)), np.empty((n, p + m))
    for j in range(n):
        (x, y), e = problem.joint_rows(j), extra[j]
        cross = x.T @ e
        out_grams[j, :p, :p], out_grams[j, :p, p:], out_grams[j, p:, :p] = grams[j], cross, cross.T
        out_grams[j, p:, p:] = e.T @ e
        out_moments[j, :p], out_moments[j, p:] = moments[j], e.T @ y
    return out_grams, out_moments, totals.copy()


def normal_equations(
    problem: Problem, weights: np.ndarray, statistics: Statistics | None = None
) -> tuple[np.ndarray, np.ndarray, float]:
    """``A + P``, ``X^T W y + P theta_0`` and ``y^T W y + theta_0^T P theta_0`` over the used rows (from
    ``statistics``, :func:`joint_statistics`, when given)."""
    grams, moments, totals = joint_statistics(problem) if statistics is None else statistics
    design = np.tensordot(weights, grams, axes=1) + np.diag(problem.prior_precision)
    moment = weights @ moments + problem.prior_precision * problem.prior_mean
    total = float(weights @ totals + (problem.prior_precision * problem.prior_mean**2).sum())
    return design, moment, total


def _scaled_cholesky(design: np.ndarray, moment: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``R, c, scale`` of :func:`triangular` for the column-scaled problem, from its normal equations (p x p);
    None where they are too ill-conditioned for Cholesky (then the tall matrix's QR is needed)."""
    scale = np.sqrt(np.clip(np.diag(design), 0.0, None))
    scale[scale == 0] = 1.0
    try:
        lower = np.linalg.cholesky(design / np.outer(scale, scale))
    except np.linalg.LinAlgError:
        return None
    if not np.linalg.cond(lower) < 1e6:
        return None
    return lower.T, np.linalg.solve(lower, moment / scale), scale


def _tall(problem: Problem, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The weighted used rows, joint by joint, and the prior rows as one tall system ``a x ~ b``."""
    root = np.sqrt(weights)
    prior_a, prior_b = prior_rows(problem)
    joints = [problem.joint_rows(j) for j in range(root.size)]
    a = np.vstack([x * root[j] for j, (x, _) in enumerate(joints)] + [prior_a])
    b = np.concatenate([y * root[j] for j, (_, y) in enumerate(joints)] + [prior_b])
    return a, b


def bounded_least_squares(a: np.ndarray, b: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """``argmin |a x - b|`` subject to ``lower <= x <= upper`` (bounds may be infinite), as
    ``scipy.optimize.lsq_linear(..., method="bvls", tol=1e-12)`` (tested against it).

    The unbounded least-squares solution where it is inside the bounds (lsq_linear's own first step, the same
    numbers); otherwise Lawson and Hanson's active set, generalised to two-sided bounds: free variables are
    solved with the others held at their bounds, a step that would leave the bounds stops at the first one it
    meets and holds that variable there, and a held variable is freed while the gradient pulls it inside. In
    numpy: scipy.optimize costs every `bsp identify` 0.13 s to import. Should the active set cycle (never seen),
    scipy's solver finishes.
    """
    x = np.linalg.lstsq(a, b, rcond=-1)[0]
    if np.all((x >= lower) & (x <= upper)):
        return np.asarray(x)
    p = a.shape[1]
    x = np.clip(x, lower, upper)
    held = (x == lower) | (x == upper)
    tolerance = 1e-12 * max(float(np.abs(a.T @ b).max()), 1e-300)
    for _ in range(10 * p + 10):
        free = ~held
        if free.any():
            target = b - a[:, held] @ x[held]
            z = np.linalg.lstsq(a[:, free], target, rcond=-1)[0]
            inside = (z >= lower[free]) & (z <= upper[free])
            if not inside.all():
                # Step from x toward z as far as the first bound it meets; hold the variables that reach one.
                current, direction = x[free], z - x[free]
                with np.errstate(divide="ignore", invalid="ignore"):
                    reach = np.where(
                        direction < 0, (lower[free] - current) / direction, (upper[free] - current) / direction
                    )
                step = float(np.clip(np.min(np.where(inside, np.inf, reach)), 0.0, 1.0))
                x[free] = np.clip(current + step * direction, lower[free], upper[free])
                at_bound = (x == lower) | (x == upper)
                held |= at_bound & free
                continue
            x[free] = z
        pull = a.T @ (b - a @ x)  # minus the gradient: where the cost falls
        release = held & (((x == lower) & (pull > tolerance)) | ((x == upper) & (pull < -tolerance)))
        if not release.any():
            return np.asarray(x)
        held[int(np.argmax(np.where(release, np.abs(pull), -np.inf)))] = False
    from scipy.optimize import lsq_linear

    return np.asarray(lsq_linear(a, b, bounds=(lower, upper), method="bvls", tol=1e-12).x)


def _bounded(problem: Problem, r_factor: np.ndarray, rhs: np.ndarray, scale: np.ndarray) -> np.ndarray:
    return bounded_least_squares(r_factor, rhs, problem.lower * scale, problem.upper * scale) / scale


def weighted_solve(problem: Problem, weights: np.ndarray, statistics: Statistics | None = None) -> np.ndarray:
    """The bounded weighted least-squares values (p,) of ``problem`` with per-joint weights ``weights`` (n,)
    (1 / sigma^2, 1/Nm^2) and its priors; from the normal equations (``statistics``: the per-joint ones, when already
    computed), or from a QR factor of the tall system when they are too ill-conditioned to factor."""
    # Column scaling makes the bounded solver's tolerances meaningful for kgm and Nm alike.
    design, moment, _ = normal_equations(problem, weights, statistics)
    factor = _scaled_cholesky(design, moment)
    if factor is not None:
        return _bounded(problem, *factor)
    a, b = _tall(problem, weights)
    scale = np.linalg.norm(a, axis=0)
    scale[scale == 0] = 1.0
    r_factor, rhs = triangular(a / scale, b)
    return _bounded(problem, r_factor, rhs, scale)


@dataclass(frozen=True)
class Reweighted:
    """The values of the per-joint reweighted fit, without its covariance: what a residual needs."""

    values: np.ndarray  # (p,)
    weights: np.ndarray  # (n,) 1 / sigma^2
    sigma: np.ndarray  # (n,) residual sd per joint at the previous values
    statistics: Statistics

    def residual(self, problem: Problem) -> np.ndarray:
        """(N, n) the residual of ``problem`` (the one solved) on its used rows, 0 elsewhere: one pass over the
        samples, which the model checks that look at the values alone do without."""
        return problem.residual(self.values)


def reweighted_values(problem: Problem) -> Reweighted:
    """Solve, then reweight twice by per-joint residual variance (Gautier and Poignet 2001)."""
    n = problem.torque.shape[1]
    weights = np.ones(n)
    statistics = joint_statistics(problem)
    values = weighted_solve(problem, weights, statistics)
    sigma = np.ones(n)
    grams, moments, totals = statistics
    counts = problem.rows.sum(axis=0)
    floor = 1e-9 * max(float(np.abs(problem.torque).max()), 1e-9)
    for _ in range(2):
        # Each joint's residual sum of squares from its statistics, y'y - 2 theta'X'y + theta'X'X theta: no pass
        # over the samples (cancellation leaves ~1e-11 of it where the fit explains the torques 1e5-fold).
        rss = totals - 2.0 * moments @ values + np.einsum("p,jpq,q->j", values, grams, values)
        sigma = np.sqrt(np.clip(rss, 0.0, None) / np.maximum(counts, 1))
        sigma = np.maximum(sigma, floor)
        weights = 1.0 / sigma**2
        values = weighted_solve(problem, weights, statistics)
    return Reweighted(values, weights, sigma, statistics)


def residual_covariance(
    problem: Problem, design: np.ndarray, weights: np.ndarray, residual: np.ndarray
) -> tuple[np.ndarray, int]:
    """The HAC sandwich of a fit of ``problem`` whose residual is ``residual`` (N, n; finite on the used rows, the
    rest ignored), with the prior's information; and the lags it chose.

    Parameters
    ----------
    problem : the problem fitted.
    design : (p, p) its weighted normal matrix (without the prior).
    weights : (n,) its per-joint weights.
    residual : (N, n) the torque residual the std is to hold, Nm.
    """
    finite = np.where(problem.rows, np.nan_to_num(residual, nan=0.0), 0.0)
    scores = joint_scores(problem, weights[None, :] * finite)
    covariance, lags = hac_covariance(design, scores[problem.rows.any(axis=1)])
    if problem.prior_precision.any():
        # The prior is an independent source of information: (A + P)^-1 (S + P) (A + P)^-1.
        inverse = design_inverse(design)
        covariance = covariance + inverse @ np.diag(problem.prior_precision) @ inverse
        covariance = 0.5 * (covariance + covariance.T)
    return covariance, lags


def fit_problem(problem: Problem, solved: Reweighted | None = None) -> Fit:
    """The reweighted fit of ``problem`` with its HAC covariance; ``solved``: its :func:`reweighted_values`, when a
    caller has them already (a model check that looks at the values first, and needs the covariance only if they
    could matter)."""
    solved = reweighted_values(problem) if solved is None else solved
    values, weights, residual = solved.values, solved.weights, solved.residual(problem)
    design, moment, _ = normal_equations(problem, weights, solved.statistics)
    covariance, lags = residual_covariance(problem, design, weights, residual)
    # Singular values of the column-scaled matrix are those of its triangular factor.
    factor = _scaled_cholesky(design, moment)
    if factor is not None:
        r_factor = factor[0]
    else:
        a, _ = _tall(problem, weights)
        norms = np.linalg.norm(a, axis=0)
        r_factor = triangular(a / np.where(norms > 0, norms, 1.0), a[:, 0])[0]
    singular = np.linalg.svd(r_factor, compute_uv=False)
    condition = float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")
    residual_used = np.where(problem.rows, residual, np.nan)
    return Fit(
        values=values,
        covariance=covariance,
        residual=residual_used,
        sigma=solved.sigma,
        condition=condition,
        lags=lags,
        design=design,
        weights=weights,
    )


def augmented(
    problem: Problem,
    extra: np.ndarray,
    names: list[ParameterName],
    prior_mean: np.ndarray | None = None,
    prior_precision: np.ndarray | None = None,
) -> Problem:
    """``problem`` with extra unbounded columns ``extra`` (N, n, m), with Gaussian priors where given."""
    m = len(names)
    own = tuple(np.where(problem.rows[:, j, None], extra[:, j], 0.0) for j in range(problem.torque.shape[1]))
    return Problem(
        names=problem.names + names,
        blocks=(*problem.blocks, own),
        torque=problem.torque,
        rows=problem.rows,
        lower=np.concatenate((problem.lower, np.full(m, -np.inf))),
        upper=np.concatenate((problem.upper, np.full(m, np.inf))),
        prior_mean=np.concatenate((problem.prior_mean, np.zeros(m) if prior_mean is None else prior_mean)),
        prior_precision=np.concatenate(
            (problem.prior_precision, np.zeros(m) if prior_precision is None else prior_precision)
        ),
        passive_end=problem.passive_end,
        joint_torques=problem.joint_torques,  # the same rows and torques
        known_statistics=_augmented_statistics(problem, own),
    )
