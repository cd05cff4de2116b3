"""Gaussian priors on the base parameters the data may not identify: inertias and perpendicular moments."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from bsp_ros.core.anthropometry import GYRATION_REL_SD, segment_norm
from bsp_ros.core.dynamics import base_parameters
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.fusion import SubjectInfo, anthropometric_prior
from bsp_ros.core.streams import segments_for

# The COM's offset from the line through the joint centres, as a share of its distance along it (1 sd): the
# tables place it on that line; a person's soft tissue and a marker-defined axis sit a degree or two off it.
PERPENDICULAR_PRIOR_FRACTION = 0.03
# Prior draws to propagate the mass, COM and radius-of-gyration spreads into the grouped inertias.
_DRAWS = 4000


@dataclass(frozen=True)
class BasePrior:
    """Gaussian priors (mean, sd) on the perpendicular moments (kg m) and grouped inertias (kg m^2), (n,) each."""

    perpendicular_mean_kgm: np.ndarray
    perpendicular_sd_kgm: np.ndarray
    inertia_mean_kgm2: np.ndarray
    inertia_sd_kgm2: np.ndarray


def base_prior(
    lengths_m: npt.ArrayLike,
    mass_mean_kg: npt.ArrayLike,
    mass_cov: npt.ArrayLike,
    com_mean_m: npt.ArrayLike,
    com_cov: npt.ArrayLike,
    sex: str = "male",
) -> BasePrior:
    """Priors on the base inertial parameters from the anthropometric prior of masses and COMs.

    Parameters
    ----------
    lengths_m : (n,) segment lengths (m).
    mass_mean_kg, com_mean_m : (n,) prior means of masses (kg) and COM distances (m).
    mass_cov, com_cov : (n, n) their prior covariances.
    sex : the table of radii of gyration (de Leva 1996).

    Returns
    -------
    BasePrior; the inertias by Monte Carlo over masses, COMs and radii (seeded: the prior is deterministic).
    """
    lengths = np.asarray(lengths_m, dtype=np.float64)
    n = lengths.size
    rng = np.random.default_rng(20240229)
    masses = np.clip(
        rng.multivariate_normal(np.asarray(mass_mean_kg, float), np.asarray(mass_cov, float), _DRAWS), 1e-3, None
    )
    coms = np.clip(
        rng.multivariate_normal(np.asarray(com_mean_m, float), np.asarray(com_cov, float), _DRAWS), 0.0, None
    )
    fractions = np.array([segment_norm(sex, s).gyration_fraction for s in segments_for(n)])
    radii = fractions * lengths * np.clip(1.0 + GYRATION_REL_SD * rng.standard_normal((_DRAWS, n)), 0.3, None)
    draws = base_parameters(lengths, masses, coms, masses * radii**2)  # (draws, 3n) at once
    static = draws[:, :n].mean(axis=0)
    inertia = draws[:, 2 * n :]
    return BasePrior(
        np.zeros(n), PERPENDICULAR_PRIOR_FRACTION * np.abs(static), inertia.mean(axis=0), inertia.std(axis=0)
    )


def base_prior_for_subject(subject: SubjectInfo, lengths_m: npt.ArrayLike) -> BasePrior:
    """:func:`base_prior` from the subject's anthropometric prior (:func:`bsp_ros.core.fusion.anthropometric_prior`).

    Kept for the last few subjects and lengths (its 4,000 draws cost 1.5 ms; a live window identifies one arm's
    lengths at 5 Hz); the arrays are read-only."""
    return _base_prior_for_subject(subject, np.asarray(lengths_m, dtype=np.float64).tobytes())


@functools.lru_cache(maxsize=8)
def _base_prior_for_subject(subject: SubjectInfo, lengths_bytes: bytes) -> BasePrior:
    lengths = np.frombuffer(lengths_bytes, dtype=np.float64)
    n = lengths.size
    prior = anthropometric_prior(subject, lengths)
    out = base_prior(
        lengths, prior.mean[:n], prior.covariance[:n, :n], prior.mean[n:], prior.covariance[n:, n:], subject.sex
    )
    for array in vars(out).values():
        array.setflags(write=False)
    return out


# A perpendicular moment this many prior sd from its prior mean is no COM off the segment axis: an effect the
# model lacks (two-joint muscles make a joint's passive moment depend on the proximal joint's angle, as gravity
# on an off-axis COM does) has been taken up as one.
PERPENDICULAR_MAX_PRIOR_SD = 4.0


def implausible_perpendicular_moments(
    segments: list[str],
    values_kgm: np.ndarray,
    prior: BasePrior,
    model_sd_kgm: np.ndarray | None = None,
    family_chosen: bool = False,
) -> list[Finding]:
    """Why the identified perpendicular moments (kg m, (n,)) cannot be a real COM offset; empty when they can.

    Parameters
    ----------
    segments : (n,) segment names.
    values_kgm : (n,) identified perpendicular moments.
    prior : the prior they were identified with.
    model_sd_kgm : (n,) how far what the data cannot tell moves each value (kg m): the passive models the data
        cannot choose between (``--passive auto``), skin markers off their joint centres; a value these alone
        could move back into the prior's range is no evidence.
    family_chosen : the data already chose among the coupled and nonlinear passive terms (``--passive auto``):
        the advice is then not to choose them.
    """
    problems = []
    spread = np.zeros(len(segments)) if model_sd_kgm is None else np.asarray(model_sd_kgm, dtype=np.float64)
    for name, value, mean, sd, extra in zip(
        segments, values_kgm, prior.perpendicular_mean_kgm, prior.perpendicular_sd_kgm, spread, strict=True
    ):
        if sd > 0 and abs(value - mean) > PERPENDICULAR_MAX_PRIOR_SD * math.hypot(sd, extra):
            values = {
                "prior_sd_off": float(abs(value - mean) / sd),
                "value_kgm": float(value),
                "family_chosen": bool(family_chosen),
            }
            problems.append(Finding(code=FindingCode.PERPENDICULAR_IMPLAUSIBLE, where=name, values=values))
    return problems
