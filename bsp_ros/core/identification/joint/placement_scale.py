"""Model check: whether the skin markers sit further off their joint centres than the placement sd assumes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.covariance import design_inverse, hac_covariance
from bsp_ros.core.identification.joint.placement_covariance import offset_names
from bsp_ros.core.identification.result import ParameterName
from bsp_ros.core.identification.stacked import (
    Problem,
    augmented,
    joint_scores,
    normal_equations,
    reweighted_values,
)

# The widest placement the data may call for, in units of the assumed sd (2 cm at the default 2 mm).
MAX_SCALE = 10.0
# The offsets' prior precision in the free fit, per sd^2: a prior sd of 100 assumed sd keeps the directions no
# data can see (offsets along the chain scale every lever arm, like the static moments) solvable, and leaves
# the others to the data.
_FREE_PRECISION = 1e-4
# A wider placement is named in the warnings when its likelihood ratio against the assumed one is this large
# (chi-square, 1 degree of freedom, p = 0.001); a smaller one still widens the std, by less.
NOTE_LIKELIHOOD_RATIO = 10.83
_GRID = np.exp(np.linspace(0.0, np.log(MAX_SCALE), 241))
# The prior probability that the markers sit as the assumed sd says; the rest is spread evenly over the log of the
# wider scales up to MAX_SCALE. The std uses the placement averaged over the scales the data leave plausible (the
# posterior mean of the squared scale), not the most likely scale alone: from one session's handful of offsets that
# is above 1 in about half of the sessions whose markers sit as assumed, and up to 2.3 (on MuJoCo arms with
# markers re-placed at the assumed sd, a std 15 % wider than the errors on average).
PRIOR_ASSUMED = 0.9


def _free_offsets(free: Problem, m: int) -> tuple[np.ndarray, np.ndarray]:
    """The last ``m`` values of the reweighted fit of ``free`` and their HAC covariance (m, m).

    As :func:`fit_problem`'s block of them, but the sandwich runs on the scores projected on those values (``B s_t``
    with ``B`` their rows of the inverse design): its lags are chosen for them, and it costs m components instead
    of every parameter's."""
    solved = reweighted_values(free)
    design, _, _ = normal_equations(free, solved.weights, solved.statistics)
    rows = design_inverse(design)[-m:, :]  # (m, P)
    weighted = solved.weights[None, :] * solved.residual(free)  # (N, n), 0 off the used rows
    # B s_t = sum_i (B x_ti) w_i r_ti: each joint's rows projected on B in one BLAS product, then the per-sample
    # scores of those projected rows (half the time of forming the (N, P) scores first).
    scores = joint_scores(free, weighted, rows.T)[free.rows.any(axis=1)]
    covariance, _ = hac_covariance(np.eye(m), scores)
    covariance = covariance + rows @ (free.prior_precision[:, None] * rows.T)
    return solved.values[-m:], 0.5 * (covariance + covariance.T)


@dataclass(frozen=True)
class PlacementScale:
    """What the data say of the markers' placement.

    Attributes
    ----------
    scale : the factor (>= 1) on the skin markers' assumed placement sd the std uses: the root of the posterior
        mean of the squared scale, averaged over the scales the data leave plausible (:data:`PRIOR_ASSUMED`).
    likelihood_ratio : ``2 log`` of the most likely scale's likelihood over the assumed placement's (0 when the
        most likely scale is 1).
    most_likely : the scale of largest marginal likelihood (>= 1): what a warning reports as the apparent placement.
    sd_m : (n + 1,) the placement sd of each chain point to use, m: the skin markers' scaled, a robot's contact
        point (its registration) as assumed.
    note : a warning when the data call for a clearly wider placement, else None.
    column_factor : (m,) what each offset column at the assumed placement is multiplied by for the used one.
    """

    scale: float
    likelihood_ratio: float
    sd_m: np.ndarray
    note: Finding | None
    column_factor: np.ndarray
    most_likely: float = 1.0

    def to_dict(self, assumed_sd_m: np.ndarray) -> dict[str, object]:
        """The estimate's ``quality.marker_placement``: assumed and used sd per chain point (mm), the scale."""
        return {
            "assumed_sd_mm": [round(1e3 * float(v), 4) for v in assumed_sd_m],
            "sd_mm": [round(1e3 * float(v), 4) for v in self.sd_m],
            "scale_from_data": round(self.scale, 3),
            "likelihood_ratio": round(self.likelihood_ratio, 2),
            "scale_most_likely": round(self.most_likely, 3),
        }


def placement_scale(
    problem: Problem,
    columns: np.ndarray,
    sd_m: np.ndarray,
    skin: np.ndarray,
    nuisance: Problem | None = None,
    modelled: tuple[np.ndarray, list[ParameterName]] | None = None,
) -> PlacementScale:
    """How far the data put the markers from their joint centres, against the assumed placement ``sd_m``.

    The offsets of every chain point are fitted with the parameters, nearly free (``d``, in units of the assumed
    sd, with its HAC covariance ``C``), beside ``nuisance``'s and ``modelled``'s columns. Offsets drawn with sd
    ``s`` times the assumed one give ``d ~ N(0, s^2 I + C)`` (for the skin markers; a robot's contact point keeps
    its own sd): the ``s >= 1`` of largest likelihood is taken. Where no data see an offset, ``C`` is large and it
    weighs nothing. On simulated sessions with the markers on their centres ``s`` is 1; with skin markers 1 cm off
    (5 times the default 2 mm), 2.1-4.3, and the std then holds the truth (``bench/realism.py``, "skin markers
    1 cm"). What else the model lacks can also raise ``s`` (the offsets take up what they can of it): a spring or
    a drift too small for their own checks is fitted beside them (``nuisance``, ``modelled``); the caller judges
    the placement only where the model checks found nothing else.

    Parameters
    ----------
    problem : the identification's problem.
    columns : (N, n, m) the offsets' columns at the assumed placement and the fit (:func:`offset_columns`).
    nuisance : a wider problem of the same samples whose extra columns are fitted beside the offsets (a linear
        spring's), or None (``problem``).
    sd_m : (n + 1,) the assumed placement sd per chain point (m).
    skin : (n + 1,) bool, which chain points are skin markers (the scale applies to them).
    modelled : extra columns (N, n, k) and their names fitted beside them too (a drift's), or None.

    Returns
    -------
    PlacementScale
    """
    m = columns.shape[2]
    names = offset_names(m)
    base = nuisance or problem
    extra, extra_names, k = columns, names, 0
    if modelled is not None:  # one pass over the samples for both sets of columns
        k = modelled[0].shape[2]
        extra, extra_names = np.concatenate((modelled[0], columns), axis=2), [*modelled[1], *names]
    precision = np.concatenate((np.zeros(k), np.full(m, _FREE_PRECISION)))
    offsets, covariance = _free_offsets(augmented(base, extra, extra_names, np.zeros(k + m), precision), m)
    # Each chain point has an along and a normal offset (columns 2k, 2k + 1), per recording where markers moved.
    scaled = np.tile(np.repeat(np.asarray(skin, dtype=bool), 2), m // (2 * len(skin)))
    finite = np.isfinite(offsets).all() and np.isfinite(covariance).all()
    judged = scale_from_offsets(offsets, covariance, scaled) if finite and scaled.any() else None
    if judged is None:
        return PlacementScale(1.0, 0.0, np.asarray(sd_m, dtype=np.float64), None, np.ones(m))
    scale, ratio, best = judged
    most_likely = float(_GRID[best])
    used = np.where(skin, np.asarray(sd_m, dtype=np.float64) * scale, sd_m)
    note = None
    if ratio > NOTE_LIKELIHOOD_RATIO:
        assumed_mm = 1e3 * float(np.max(np.where(skin, sd_m, 0.0)))
        values = {"assumed_mm": assumed_mm, "apparent_mm": most_likely * assumed_mm, "at_limit": best == _GRID.size - 1}
        note = Finding(code=FindingCode.PLACEMENT_WIDER, values=values)
    return PlacementScale(scale, ratio, used, note, np.where(scaled, scale, 1.0), most_likely=most_likely)


def seen_directions(covariance: np.ndarray) -> np.ndarray:
    """(m, k) orthonormal directions of the free offsets (in units of their assumed sd) the data measure better
    than the assumed placement does: the eigenvectors of their covariance ``covariance`` (m, m) with variance
    below 1.

    Only these judge the placement. Along the others the fit hardly moves the torques (where the handle force keeps
    nearly one direction, the shoulder marker's offset along the upper arm scales its gravity torque as the upper
    arm's static moment does), so whatever small misfit the model leaves weighs there 1 / variance times over and
    would read as markers far off; the placement prior carries those directions in the std as assumed.
    """
    variance, vectors = np.linalg.eigh(0.5 * (covariance + covariance.T))
    return np.asarray(vectors[:, variance < 1.0])


def scale_from_offsets(
    offsets: np.ndarray, covariance: np.ndarray, scaled: np.ndarray
) -> tuple[float, float, int] | None:
    """The placement scale the free offsets call for.

    Parameters
    ----------
    offsets : (m,) the free offsets, in units of their assumed sd.
    covariance : (m, m) their covariance, same units.
    scaled : (m,) bool, which offsets the scale applies to (the others keep variance 1).

    Returns
    -------
    The scale the std uses (:func:`averaged_scale`), ``2 log`` of the most likely scale's likelihood over the
    assumed one's, and the index of the most likely scale in :data:`_GRID`; None where the data see no direction
    (:func:`seen_directions`).
    """
    seen = seen_directions(covariance)
    if seen.shape[1] == 0:
        return None
    variance = np.where(scaled[None, :], _GRID[:, None] ** 2, 1.0)  # (grid, m) the offsets' prior variance
    prior = np.einsum("mk,gm,ml->gkl", seen, variance, seen)  # (grid, k, k) that prior along the seen directions
    spread = (seen.T @ covariance @ seen)[None, :, :] + prior
    seen_offsets = seen.T @ offsets
    _, log_det = np.linalg.slogdet(spread)
    solved = np.linalg.solve(spread, np.broadcast_to(seen_offsets[:, None], (_GRID.size, seen.shape[1], 1)))[..., 0]
    minus_log_likelihood = 0.5 * (log_det + solved @ seen_offsets)
    best = int(np.argmin(minus_log_likelihood))
    ratio = float(2.0 * (minus_log_likelihood[0] - minus_log_likelihood[best]))
    return averaged_scale(minus_log_likelihood), ratio, best


def averaged_scale(minus_log_likelihood: np.ndarray) -> float:
    """The root of the posterior mean of the squared scale over :data:`_GRID`, from the offsets' minus log
    likelihood there (same shape): the assumed scale 1 with prior probability :data:`PRIOR_ASSUMED`, the wider ones
    sharing the rest evenly."""
    log_prior = np.full(_GRID.size, np.log((1.0 - PRIOR_ASSUMED) / (_GRID.size - 1)))
    log_prior[0] = np.log(PRIOR_ASSUMED)
    log_posterior = log_prior - minus_log_likelihood
    weights = np.exp(log_posterior - log_posterior.max())
    return float(np.sqrt(np.sum(weights * _GRID**2) / np.sum(weights)))
