"""Choice of the passive model by the data (``--passive auto``), and what the choice leaves uncertain."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bsp_ros.core.identification.chi2 import chi2_sf
from bsp_ros.core.identification.covariance import design_inverse
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.stacked import (
    Extras,
    Fit,
    Problem,
    build_problem,
    fit_problem,
    joint_products,
    problem_names,
    residual_covariance,
)

# A candidate is rejected by the data when the terms it leaves out differ from 0 at this level (HAC Wald test on
# the richest fit); the others are the models the data cannot reject, whose estimates must agree within the std.
REJECT_P = 0.01


@dataclass(frozen=True)
class Candidate:
    """One passive model the data were asked about: its problem, fit, criterion and weight."""

    model: PassiveModel
    problem: Problem | None
    fit: Fit | None
    criterion: float  # BIC-like, relative to the richest model (smaller is better)
    weight: float  # posterior-like weight, exp(-criterion / 2), normalised over the candidates
    p_value: float  # of the terms it leaves out (1 for the richest model)

    @property
    def rejected(self) -> bool:
        """Whether the data reject this model (:data:`REJECT_P`)."""
        return self.p_value < REJECT_P


@dataclass(frozen=True)
class Selection:
    """The chosen model (smallest criterion), every candidate, and the chosen model's shape probe (if any)."""

    chosen: Candidate
    candidates: list[Candidate]
    probe: Candidate | None = None

    def to_dict(self) -> dict[str, dict[str, float]]:
        """``{label: {"criterion", "weight", "p_value", "rejected"}}`` for ``diagnostics.passive_selection``."""
        return {
            c.model.label: {"criterion": c.criterion, "weight": c.weight, "p_value": c.p_value, "rejected": c.rejected}
            for c in self.candidates
        }

    @property
    def open_models(self) -> list[Candidate]:
        """The models whose estimates the chosen one's std must cover: the candidates the data cannot reject, and
        the shape probe."""
        others = [c for c in self.candidates if c is not self.chosen and not c.rejected and c.fit is not None]
        return others + ([self.probe] if self.probe is not None else [])


def select_passive(
    data: IdentificationData,
    model: PassiveModel,
    rows: np.ndarray,
    widths: np.ndarray | None,
    extras: Extras | None,
    covariance_of: Callable[[Problem, Fit], np.ndarray] | None = None,
) -> Selection:
    """Choose among ``model.candidates()`` by a Wald-form BIC, each model tested inside the richer ones.

    Every candidate is fitted. A candidate that leaves out terms of a richer one is scored in that richer model's
    fit: the HAC Wald statistic of the terms it leaves out (autocorrelation-robust, unlike a likelihood ratio on
    correlated residuals) minus ``ln N`` per term, N the used torque rows (Schwarz 1978; the Wald form as in Kass
    and Raftery 1995), plus the richer model's own criterion: the criterion relative to the richest model along
    the least favourable chain of nested models. Testing inside each richer model, not only inside the richest,
    keeps the tests' power where the richest model cannot tell its terms from gravity (its covariance, right, is
    then too wide to reject anything, and the simplest model would win however strong a spring). A candidate is
    rejected when any of its tests rejects at :data:`REJECT_P`; the choice is the smallest criterion among the
    models not rejected. Weights ``exp(-criterion / 2)`` are reported;
    the models the data cannot reject enter :func:`spread_covariance`. ``covariance_of`` gives a fit's full
    covariance for the tests (the marker placement's share included: offsets of skin markers bend the torques
    like elastic terms, and a test on the sensor noise alone would reject every simple model of a precise
    session).
    """
    models = model.candidates()
    n = data.n_joints
    problems = [build_problem(data, m, rows, widths, extras) for m in models]
    fits = [fit_problem(problem) for problem in problems]
    covariances = [
        f.covariance if covariance_of is None else covariance_of(p, f) for p, f in zip(problems, fits, strict=True)
    ]
    names = [set(problem_names(m, n, extras is not None)) for m in models]
    penalty = float(np.log(max(int(rows.sum()), 2)))
    criteria = [0.0] * len(models)
    p_values = [1.0] * len(models)
    # From the richest down: every richer model's criterion is known when a simpler one is scored against it.
    for i in range(len(models) - 2, -1, -1):
        scores = []
        for j in range(i + 1, len(models)):
            if not names[i] < names[j]:
                continue
            left_out = [k for k, name in enumerate(problems[j].names) if name not in names[i]]
            theta = fits[j].values[left_out]
            sub = covariances[j][np.ix_(left_out, left_out)]
            # Directions the data cannot test (terms confounded with gravity, held by their priors) carry no
            # evidence: a relative cut keeps their near-zero eigenvalues from turning rounding into significance.
            statistic = float(theta @ np.linalg.pinv(sub, rcond=1e-6, hermitian=True) @ theta)
            scores.append(statistic - penalty * len(left_out) + criteria[j])
            p_values[i] = min(p_values[i], float(chi2_sf(statistic, len(left_out))))
        criteria[i] = max(scores) if scores else 0.0
    criterion = np.array(criteria)
    weight = np.exp(-0.5 * (criterion - criterion.min()))
    weight /= weight.sum()
    # The smallest criterion among the models the data do not reject (all, if every one is rejected).
    open_ = np.array([p >= REJECT_P for p in p_values])
    best = int(np.argmin(np.where(open_, criterion, np.inf))) if open_.any() else int(np.argmin(criterion))
    candidates = [
        Candidate(m, problems[i], fits[i], float(criterion[i]), float(weight[i]), p_values[i])
        for i, m in enumerate(models)
    ]
    chosen = candidates[best]
    return Selection(chosen, candidates, shape_probe(data, chosen, rows, widths, extras))


def shape_probe(
    data: IdentificationData, chosen: Candidate, rows: np.ndarray, widths: np.ndarray | None, extras: Extras | None
) -> Candidate | None:
    """The chosen nonlinear model with the elastic potential's next order (``higher``), fitted: nothing above
    the richest candidate tests how far its estimate hangs on the assumed shape of the passive curves.

    Around one posture a polynomial in the joint angles mimics gravity's cosine, so the static moments are told
    from the passive moments by curvature alone; a true curve (a muscle's exponential) that the polynomial
    follows closely but not exactly then moves them by several of their std (arm26 at 10 % of gravity, one
    posture: forearm +116 % at 4 std). The probe's shift joins the std; with a second posture it is small.
    """
    if "nonlinear" not in chosen.model.terms or "higher" in chosen.model.terms:
        return None
    model = chosen.model.with_terms(("higher",))
    problem = build_problem(data, model, rows, widths, extras)
    return Candidate(model, problem, fit_problem(problem), 0.0, 0.0, 1.0)


def spread_covariance(
    selection: Selection, offset_columns: np.ndarray | None = None, residual: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """What the model choice leaves uncertain: per parameter of the chosen model, the largest squared difference
    to the estimate of any candidate the data cannot reject (the richest one included), at least the variance that
    difference has where both models hold, or to the shape probe's (plus the probe's variance beyond the chosen
    fit's), as a diagonal covariance (p, p), and that difference in units of the chosen fit's std (p,), for the
    warnings. ``offset_columns`` (N, n, m): the marker offsets' columns at their assumed sd, whose share of that
    variance joins the sensor noise's; None without placement. ``residual`` (N, n): the chosen fit's residual once
    the offsets took what they explain, on which every model's sensor-noise variance is judged (None: each fit's
    own).

    A static moment is trusted only as far as it is stable across the passive models the data leave open:
    a simpler model is more precise only if its restrictions hold, which the data may be unable to test when
    the left-out terms are confounded with gravity (then the richer models' estimates differ and say so).
    """
    chosen = selection.chosen
    assert chosen.problem is not None and chosen.fit is not None
    names = chosen.problem.names
    p = len(names)
    spread = np.zeros(p)
    std = np.sqrt(np.clip(np.diag(chosen.fit.covariance), 1e-300, None))
    mine = None if offset_columns is None else placement_response(chosen, offset_columns)
    base = _noise_variance(chosen, residual)
    for candidate in selection.open_models:
        assert candidate.fit is not None and candidate.problem is not None
        theirs = {name: i for i, name in enumerate(candidate.problem.names)}
        shared = [i for i, name in enumerate(names) if name in theirs]
        d = np.zeros(p)
        picks = [theirs[names[i]] for i in shared]
        d[shared] = candidate.fit.values[picks] - chosen.fit.values[shared]
        excess = np.zeros(p)
        excess[shared] = np.clip(_noise_variance(candidate, residual)[picks] - base[shared], 0, None)
        if candidate is selection.probe:
            # The probe's own std too, where larger: with the next order free, the curvature that told the static
            # moments from the passive moments may be gone (one posture), and the std says so.
            spread = np.maximum(spread, d**2 + excess)
            continue
        if mine is not None and offset_columns is not None:
            moved = placement_response(candidate, offset_columns)[picks] - mine[shared]
            excess[shared] += np.sum(moved**2, axis=1)
        # Where both models hold, the difference of a richer model's fit from the chosen one's has about the variance
        # of their difference in variance (Hausman) plus what the markers' placement moves them apart: its square is
        # one draw of that, 0.004-4 times it in 90 % of sessions. The larger of the two is as large on average and
        # follows the data where the models differ by more, without a std that jumps 5-10 times between sessions.
        spread = np.maximum(spread, np.maximum(d**2, excess))
    return np.diag(spread), np.sqrt(spread) / std


def _noise_variance(candidate: Candidate, residual: np.ndarray | None) -> np.ndarray:
    """(p,) a candidate's sensor-noise variances: its fit's own, or (``residual`` (N, n)) the HAC sandwich of
    that residual at its weights. A model's own residual holds what the markers' offsets bend the torques by, which
    the placement share counts already: a nonlinear open model's wrist offset read 0.17 Nm of noise where the
    markers were re-placed by 2 mm and 0.02 where they sat on the centres."""
    assert candidate.problem is not None and candidate.fit is not None
    if residual is None:
        return np.diag(candidate.fit.covariance)
    covariance, _ = residual_covariance(candidate.problem, candidate.fit.design, candidate.fit.weights, residual)
    return np.diag(covariance)


def placement_response(candidate: Candidate, offset_columns: np.ndarray) -> np.ndarray:
    """(p, m) how a candidate's fit moves with marker offsets of one assumed sd along ``offset_columns`` (N, n, m):
    ``(A + P)^-1 X^T W D`` at its weights."""
    assert candidate.problem is not None and candidate.fit is not None
    products = joint_products(candidate.problem, candidate.fit.weights, offset_columns)
    return np.asarray(design_inverse(candidate.fit.design) @ products)
