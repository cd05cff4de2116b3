"""The numpy stand-ins that keep scipy.special, scipy.ndimage and scipy.optimize off `bsp identify`'s imports, each
against the scipy function it replaces (an independent implementation)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy import ndimage, optimize, special

from bsp_ros.core.identification.chi2 import chi2_sf
from bsp_ros.core.identification.robust import _nanmedian, robust_sd, rolling_median
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


@pytest.mark.parametrize("rows", [20, 599, 600, 1501, 30_000])
@pytest.mark.parametrize("axis", [0, 1])
def test_nanmedian_is_numpys_bit_for_bit(rows: int, axis: int) -> None:
    rng = np.random.default_rng(rows + axis)
    values = rng.normal(size=(rows, 3) if axis == 0 else (3, rows))
    values[rng.random(values.shape) < 0.3] = np.nan  # residuals are NaN off a joint's used rows
    for keepdims in (False, True):
        expected = np.nanmedian(values, axis=axis, keepdims=keepdims)
        got = _nanmedian(values, axis, keepdims)
        assert got.shape == expected.shape and np.array_equal(got, expected)


@pytest.mark.parametrize("rows", [20, 1501])
def test_nanmedian_of_a_joint_without_used_rows_is_nan(rows: int) -> None:
    values = np.random.default_rng(rows).normal(size=(rows, 3))
    values[:, 1] = np.nan
    values[::3, 2] = np.nan
    with pytest.warns(RuntimeWarning):  # numpy warns of the all-NaN column (and so below 600 rows, its route)
        expected = np.nanmedian(values, axis=0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        got = _nanmedian(values, 0)
    assert np.isnan(got[1]) and np.array_equal(got, expected, equal_nan=True)


def test_robust_sd_of_a_gaussian_sample_with_outliers() -> None:
    values = np.random.default_rng(5).normal(0.0, 2.0, size=(20_000, 2))
    values[::50] = 1e6  # 2 % wild samples barely move the median absolute deviation
    values[1::7, 1] = np.nan
    assert robust_sd(values, axis=0) == pytest.approx([2.0, 2.0], rel=0.05)


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
