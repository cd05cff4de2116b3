"""The HAC covariance: the Bartlett long-run sum and the correlation length against their definitions."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core.identification.covariance import bartlett_long_run, correlation_length, fft_length


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


def test_fft_length_is_the_smallest_5_smooth_length_reaching_the_minimum() -> None:
    smooth = sorted(2**a * 3**b * 5**c for a in range(22) for b in range(14) for c in range(10))
    for minimum in [*range(1, 400), 60_501, 120_001, 600_501, 131_072, 131_073]:
        expected = next(v for v in smooth if v >= minimum)
        assert fft_length(minimum) == expected, minimum


def test_correlation_length_is_the_first_lag_inside_the_noise_band() -> None:
    # AR(1) scores with coefficient 0.9: the autocorrelation at lag l is 0.9^l, inside 2/sqrt(N) from the lag
    # the direct sum says (computed here without an FFT).
    rng = np.random.default_rng(5)
    n = 6001
    noise = rng.normal(size=(n, 3))
    scores = np.empty_like(noise)
    scores[0] = noise[0]
    for t in range(1, n):
        scores[t] = 0.9 * scores[t - 1] + noise[t]
    centred = scores - scores.mean(axis=0)
    variance = (centred**2).sum(axis=0)
    band = 2.0 / np.sqrt(n)
    expected = next(
        lag
        for lag in range(1, n // 4)
        if all(abs((centred[lag:, k] * centred[:-lag, k]).sum() / variance[k]) < band for k in range(3))
    )
    assert correlation_length(scores) == expected
