"""Priors on the base parameters the data may not identify, and the plausibility of what the fit made of them."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.findings import FindingCode
from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.identification.priors import (
    PERPENDICULAR_MAX_PRIOR_SD,
    base_prior_for_subject,
    implausible_perpendicular_moments,
)

SEGMENTS = ["upper_arm", "forearm", "hand"]


def test_the_inertia_prior_holds_the_de_leva_table_arm() -> None:
    prior = base_prior_for_subject(SubjectInfo(75.0, None, "male"), np.array([0.288, 0.275, 0.088]))
    # The table arm's grouped inertias (de Leva radii, masses and COMs for 75 kg): 0.207, 0.060, 0.0032 kg m^2.
    table = np.array([0.2071, 0.0602, 0.00315])
    assert np.all(np.abs(prior.inertia_mean_kgm2 - table) < 0.5 * prior.inertia_sd_kgm2)
    assert np.all(prior.inertia_sd_kgm2 > 0.1 * table)


def test_an_off_axis_moment_beyond_the_prior_is_named_and_one_within_is_not() -> None:
    prior = base_prior_for_subject(SubjectInfo(75.0, None, "male"), np.array([0.288, 0.275, 0.088]))
    sd = prior.perpendicular_sd_kgm
    within = 0.9 * PERPENDICULAR_MAX_PRIOR_SD * sd
    assert implausible_perpendicular_moments(SEGMENTS, within, prior) == []
    beyond = within.copy()
    beyond[1] = -1.2 * PERPENDICULAR_MAX_PRIOR_SD * sd[1]
    problems = implausible_perpendicular_moments(SEGMENTS, beyond, prior)
    assert [(f.code, f.where) for f in problems] == [(FindingCode.PERPENDICULAR_IMPLAUSIBLE, "forearm")]
    assert "two-joint" in problems[0].text and not problems[0].values["family_chosen"]
    # Where the data already chose among the coupled and nonlinear terms (--passive auto), choosing them is no advice.
    (chosen,) = implausible_perpendicular_moments(SEGMENTS, beyond, prior, family_chosen=True)
    assert "--passive auto chooses" not in chosen.text and "more nonlinear than the model" in chosen.text
