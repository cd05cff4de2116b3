"""The HAC covariance: the Bartlett long-run sum against its definition."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core.identification.covariance import bartlett_long_run


@pytest.mark.parametrize("lags", [0, 1, 7, 120])
def test_bartlett_long_run_equals_the_weighted_sum_over_lags(lags: int) -> None:
    rng = np.random.default_rng(11)
    scores = np.cumsum(rng.normal(size=(500, 4)), axis=0) * 0.1  # strongly autocorrelated, like filtered errors
    centred = scores - scores.mean(axis=0)
    expected = centred.T @ centred
    for lag in range(1, lags + 1):
        gamma = centred[lag:].T @ centred[:-lag]
        expected += (1.0 - lag / (lags + 1.0)) * (gamma + gamma.T)
    np.testing.assert_allclose(
        bartlett_long_run(centred, lags), expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max()
    )
