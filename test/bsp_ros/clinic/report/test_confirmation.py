"""The level of a confirmed change keeps an unchanged arm's chance of any flag in a report at 5 %."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import multivariate_normal
from scipy.stats import t as student

from bsp_ros.clinic.report.confirmation import confirmation_alpha, confirmation_chance

VISITS = 6


def _any_flag_rate(series: int, pairs: int, alpha: float, rng: np.random.Generator, sims: int = 100_000) -> float:
    """Monte Carlo of reports of an unchanged arm: ``series`` parameters over six visits (the difference of two
    visits of sd 1), the retest SD estimated from ``pairs`` pairs; a step flagged when it and the next visit's
    difference from the same earlier visit are both beyond Student's t at ``alpha`` times that SD, one way."""
    x = rng.normal(0.0, np.sqrt(0.5), (sims, series, VISITS))
    sd = np.sqrt(rng.chisquare(pairs, (sims, series)) / pairs)[..., None]
    step, confirm = x[:, :, 1:-1] - x[:, :, :-2], x[:, :, 2:] - x[:, :, :-2]
    limit = student.ppf(1.0 - alpha / 2.0, pairs) * sd
    flagged = (np.abs(step) > limit) & (np.abs(confirm) > limit) & (step * confirm > 0)
    return float(flagged.any(axis=(1, 2)).mean())


@pytest.mark.parametrize(("series", "pairs"), [(4, 6), (5, 6), (5, 35), (6, 29)])
def test_the_level_for_n_confirmations_keeps_any_flag_at_five_percent(series: int, pairs: int) -> None:
    confirmations = series * (VISITS - 2)
    alpha = confirmation_alpha(confirmations, pairs)
    assert 0.005 < alpha < 0.03  # far looser than Bonferroni's 0.05 / N for one comparison, far tighter than 0.05
    rate = _any_flag_rate(series, pairs, alpha, np.random.default_rng(53 + series + pairs))
    # At most 5 % (Monte Carlo error about 0.07 %), and not far below: the level is calibrated, not just safe.
    assert 0.035 < rate <= 0.0515, rate
    # At the single comparison's 95 % the same rule would flag an unchanged arm in most reports' worth.
    assert _any_flag_rate(series, pairs, 0.05, np.random.default_rng(7)) > 0.12


def test_the_chance_of_one_confirmation_is_the_bivariate_normal_orthant() -> None:
    """Owen's T against scipy's bivariate normal, at one SD ratio (many pairs: the estimated SD is the true)."""
    factor = 2.3
    expected = 2.0 * multivariate_normal.cdf([-factor, -factor], mean=[0.0, 0.0], cov=[[1.0, 0.5], [0.5, 1.0]])
    assert confirmation_chance(factor, 10**7) == pytest.approx(expected, rel=2e-3)
    # Few pairs: the SD estimate's spread makes a confirmation likelier at the same factor.
    assert confirmation_chance(factor, 6) > 1.2 * expected
