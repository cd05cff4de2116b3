"""The numpy stand-ins that keep scipy.special, scipy.ndimage and scipy.optimize off `bsp identify`'s imports, each
against the scipy function it replaces (an independent implementation)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage, optimize, special

from bsp_ros.core.identification.chi2 import chi2_sf
from bsp_ros.core.identification.robust import rolling_median
from bsp_ros.core.identification.stacked import bounded_least_squares


@pytest.mark.parametrize("dof", [1, 2, 3, 6, 13, 30])
def test_chi_square_survival_matches_scipy(dof: int) -> None:
    for statistic in np.concatenate((np.geomspace(1e-6, 1500.0, 60), [0.5, 1.0, float(dof)])):
        expected = float(special.chdtrc(dof, statistic))
        assert chi2_sf(float(statistic), dof) == pytest.approx(expected, rel=1e-11, abs=1e-300)
    assert chi2_sf(0.0, dof) == 1.0 and chi2_sf(np.inf, dof) == 0.0


@pytest.mark.parametrize("size", [3, 11])
def test_rolling_median_is_ndimages_bit_for_bit(size: int) -> None:
    columns = np.random.default_rng(size).normal(size=(500, 3))
    columns[100:104] = 40.0  # a glitch the median must step over
    expected = ndimage.median_filter(columns, size=(size, 1), mode="nearest")
    assert np.array_equal(rolling_median(columns, size), expected)


@pytest.mark.parametrize("seed", range(6))
def test_bounded_least_squares_matches_scipys_bvls(seed: int) -> None:
    rng = np.random.default_rng(seed)
    p = 8
    r_factor = np.triu(rng.normal(size=(p, p))) + 3.0 * np.eye(p)
    target = rng.normal(size=p) * 3.0
    lower = np.where(rng.random(p) < 0.5, 0.0, -np.inf)
    upper = np.full(p, np.inf)
    expected = optimize.lsq_linear(r_factor, target, bounds=(lower, upper), method="bvls", tol=1e-12).x
    np.testing.assert_allclose(bounded_least_squares(r_factor, target, lower, upper), expected, atol=1e-9)
