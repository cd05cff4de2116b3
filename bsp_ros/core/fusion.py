"""Masses and centres of mass: anthropometric Gaussian prior fused with identified static moments (MAP)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from bsp_ros.core.anthropometry import (
    DEFAULT_BODY_MASS_KG,
    DEFAULT_BODY_MASS_SD_KG,
    check_body_mass_kg,
    check_sex,
    segment_norm,
)
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.model import static_moments_jacobian, static_moments_kgm
from bsp_ros.core.streams import segments_for
from bsp_ros.validation import check_finite_array

# Above this share of prior information in a posterior variance, the data said next to nothing.
PRIOR_DOMINATED = 0.9


@dataclass(frozen=True)
class SubjectInfo:
    """What is known of the subject (pseudonymous: no identifying data).

    Attributes
    ----------
    body_mass_kg : None when not given: then a wide population prior is used, and the result says so.
    height_m : used only where a segment length is not measured.
    sex : ``male`` or ``female``; the anthropometric table to use.
    """

    body_mass_kg: float | None = None
    height_m: float | None = None
    sex: str = "male"

    def __post_init__(self) -> None:
        check_sex(self.sex)
        if self.body_mass_kg is not None:
            check_body_mass_kg(self.body_mass_kg)
        if self.height_m is not None:
            from bsp_ros.core.anthropometry import check_height_m

            check_height_m(self.height_m)


@dataclass(frozen=True)
class Prior:
    """Gaussian prior on ``x = [m_1..m_n, l_1..l_n]`` (kg, m): mean (2n,) and covariance (2n, 2n)."""

    mean: np.ndarray
    covariance: np.ndarray
    notes: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class Posterior:
    """MAP masses and COMs with their covariance, and how much of each came from the data.

    Attributes
    ----------
    mean : (2n,) ``[m_1..m_n (kg), l_1..l_n (m)]``.
    covariance : (2n, 2n).
    prior_share : (2n,) posterior variance / prior variance: near 1 means the prior alone decided.
    first_moments_kgm : (n,) ``m_j l_j``; ``first_moments_std_kgm`` their standard deviations.
    notes : what the prior assumed.
    first_moments_prior_share : (n,) each first moment's posterior variance over its prior variance (both by the
        delta method): a first moment can be known from the data where its mass and COM alone are not (the hand's is
        its static moment), and prior alone where the static moments tell nothing.
    """

    mean: np.ndarray
    covariance: np.ndarray
    prior_share: np.ndarray
    first_moments_kgm: np.ndarray
    first_moments_std_kgm: np.ndarray
    notes: list[str]
    first_moments_prior_share: np.ndarray

    def source(self, index: int) -> str:
        """``"prior"`` when the data hardly moved parameter ``index``, else ``"data+prior"``."""
        return "prior" if self.prior_share[index] > PRIOR_DOMINATED else "data+prior"

    def first_moment_source(self, index: int) -> str:
        """``"prior"`` when the data hardly moved first moment ``index``, else ``"data+prior"``."""
        return "prior" if self.first_moments_prior_share[index] > PRIOR_DOMINATED else "data+prior"


def anthropometric_prior(subject: SubjectInfo, lengths_m: np.ndarray) -> Prior:
    """The de Leva table as a Gaussian prior on masses and COM distances of the measured segments.

    Parameters
    ----------
    subject : sex and (optionally) body mass.
    lengths_m : (n,) measured segment lengths (m); COM priors scale with them.

    Returns
    -------
    Prior on ``[m_1..m_n, l_1..l_n]``. Without a body mass, masses share the uncertainty of a population
    body mass, so they are correlated.
    """
    lengths = check_finite_array("segment lengths (m)", lengths_m, (None,))
    segments = segments_for(lengths.size)
    norms = [segment_norm(subject.sex, s) for s in segments]
    notes = []
    if subject.body_mass_kg is None:
        body_mass, body_mass_sd = DEFAULT_BODY_MASS_KG[subject.sex], DEFAULT_BODY_MASS_SD_KG
        notes.append(
            f"no body mass given: masses use a population prior ({body_mass:g} +- {body_mass_sd:g} kg, {subject.sex})"
        )
    else:
        body_mass, body_mass_sd = subject.body_mass_kg, 0.0
    fractions = np.array([nm.mass_fraction for nm in norms])
    fraction_sd = np.array([nm.mass_fraction_sd for nm in norms])
    mass_mean = fractions * body_mass
    # m = f M with f and M independent: var = (f sd_M)^2 (shared by all segments) + (M sd_f)^2.
    mass_cov = np.outer(fractions, fractions) * body_mass_sd**2 + np.diag((fraction_sd * body_mass) ** 2)
    com_mean = np.array([nm.com_fraction for nm in norms]) * lengths
    com_sd = np.array([nm.com_fraction_sd for nm in norms]) * lengths
    n = lengths.size
    covariance = np.zeros((2 * n, 2 * n))
    covariance[:n, :n] = mass_cov
    covariance[n:, n:] = np.diag(com_sd**2)
    notes.append(f"masses and COMs: de Leva (1996) {subject.sex} table as prior, fused with the static moments")
    return Prior(np.concatenate((mass_mean, com_mean)), covariance, notes)


def _gauss_newton(
    residual: Callable[[np.ndarray], np.ndarray],
    jacobian: Callable[[np.ndarray], np.ndarray],
    start: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
) -> np.ndarray:
    """The bounded least-squares minimum of ``|residual(x)|^2`` from ``start``: Gauss-Newton steps while they stay
    inside the bounds and lower the cost (the prior makes the problem well posed and nearly linear: a few steps);
    scipy's bounded solver (dogbox) where a bound binds or a step fails, imported then only (0.13 s)."""
    x = start.copy()
    r = residual(x)
    cost = float(r @ r)
    for _ in range(50):
        j = jacobian(x)
        try:
            # The normal equations: the prior's rows keep them well conditioned (lstsq's SVD cost 3x as much).
            step = np.linalg.solve(j.T @ j, -(j.T @ r))
        except np.linalg.LinAlgError:
            step = np.linalg.lstsq(j, -r, rcond=None)[0]
        candidate = x + step
        if not np.all((candidate > lower) & (candidate < upper)):
            break
        r_candidate = residual(candidate)
        new_cost = float(r_candidate @ r_candidate)
        if new_cost > cost * (1.0 + 1e-12) + 1e-300:
            break
        x, r, cost = candidate, r_candidate, new_cost
        if np.all(np.abs(step) <= 1e-12 * (1.0 + np.abs(x))):
            return x
    from scipy.optimize import least_squares

    # dogbox, as scipy advises for small bounded problems: ~5 evaluations where trf's reflective steps take ~25.
    return np.asarray(least_squares(residual, x, jac=jacobian, bounds=(lower, upper), method="dogbox", x_scale="jac").x)


def fuse_static_moments(
    prior: Prior, lengths_m: np.ndarray, beta_kgm: np.ndarray, beta_covariance: np.ndarray
) -> Posterior:
    """Maximum a posteriori masses and COMs given identified static moments.

    Minimises ``|L_b^-1 (beta(x) - beta_hat)|^2 + |L_p^-1 (x - mu)|^2`` where ``beta(x)`` is
    :func:`bsp_ros.core.model.static_moments_kgm`; the posterior covariance is the inverse Gauss-Newton Hessian.

    Parameters
    ----------
    prior : Gaussian prior on ``[m, l]``.
    lengths_m : (n,) segment lengths (m).
    beta_kgm : (n,) identified static moments (kg m).
    beta_covariance : (n, n) their covariance.

    Returns
    -------
    Posterior.
    """
    n = lengths_m.size
    beta_cov = 0.5 * (beta_covariance + beta_covariance.T) + np.eye(n) * 1e-18
    data_whiten = np.linalg.inv(np.linalg.cholesky(beta_cov))
    prior_whiten = np.linalg.inv(np.linalg.cholesky(prior.covariance))

    def residual(x: np.ndarray) -> np.ndarray:
        model = static_moments_kgm(lengths_m, x[:n], x[n:])
        return np.concatenate((data_whiten @ (model - beta_kgm), prior_whiten @ (x - prior.mean)))

    def jacobian(x: np.ndarray) -> np.ndarray:
        return np.vstack((data_whiten @ static_moments_jacobian(lengths_m, x[:n], x[n:]), prior_whiten))

    lower = np.full(2 * n, 1e-6)
    upper = np.concatenate((np.full(n, 50.0), 1.5 * lengths_m))
    start = np.clip(prior.mean, lower * 2, upper * 0.99)
    x = _gauss_newton(residual, jacobian, start, lower, upper)
    full_jacobian = jacobian(x)
    covariance = np.linalg.inv(full_jacobian.T @ full_jacobian)
    prior_share = np.diag(covariance) / np.diag(prior.covariance)
    masses, coms = x[:n], x[n:]
    first = masses * coms
    # Delta method for m l, after the data and before them (at the prior's mean).
    grad = np.hstack((np.diag(coms), np.diag(masses)))
    first_std = np.sqrt(np.diag(grad @ covariance @ grad.T))
    prior_grad = np.hstack((np.diag(prior.mean[n:]), np.diag(prior.mean[:n])))
    prior_first_var = np.diag(prior_grad @ prior.covariance @ prior_grad.T)
    first_share = first_std**2 / np.maximum(prior_first_var, 1e-300)
    return Posterior(x, covariance, prior_share, first, first_std, list(prior.notes), first_share)


# Static moments outside this factor of the anthropometric prior's are not a human arm (nor an arm with
# a handle): a lost transform, a wrong sensor frame or damaged data.
PLAUSIBLE_FACTOR = 4.0


def implausible_static_moments(
    subject: SubjectInfo,
    lengths_m: np.ndarray,
    beta_kgm: np.ndarray,
    factor: float = PLAUSIBLE_FACTOR,
    beta_std_kgm: np.ndarray | None = None,
) -> list[Finding]:
    """What is physically implausible in identified static moments, judged against the anthropometric prior.

    Parameters
    ----------
    subject : the subject facts of the prior.
    lengths_m : (n,) segment lengths (m).
    beta_kgm : (n,) identified static moments (kg m).
    factor : a static moment below ``1/factor`` or above ``factor`` times the prior's is implausible.
    beta_std_kgm : (n,) their std (kg m): a value whose 3 std reach into the plausible range is not implausible
        (an honest, wide estimate is no evidence of a fault: one posture with the full elastic family).

    Returns
    -------
    One message per implausible segment (empty when all are plausible).
    """
    lengths = np.asarray(lengths_m, dtype=np.float64)
    prior = anthropometric_prior(subject, lengths)
    n = lengths.size
    expected = static_moments_kgm(lengths, prior.mean[:n], prior.mean[n:])
    std = np.zeros(n) if beta_std_kgm is None else np.nan_to_num(np.asarray(beta_std_kgm, dtype=np.float64))
    problems = []
    for segment, value, typical, margin in zip(
        segments_for(n), np.asarray(beta_kgm, dtype=np.float64), expected, 3.0 * std, strict=True
    ):
        if not (np.isfinite(value) and typical / factor <= value + margin and value - margin <= typical * factor):
            values = {"value_kgm": float(value), "typical_kgm": float(typical), "factor": float(factor)}
            problems.append(Finding(code=FindingCode.STATIC_MOMENT_IMPLAUSIBLE, where=segment, values=values))
    return problems
