"""Parameter covariance that stays honest when residuals are autocorrelated (Newey-West HAC)."""

from __future__ import annotations

import numpy as np


def bartlett_bandwidth(scores: np.ndarray) -> int:
    """Newey-West lag truncation by Andrews' (1991) AR(1) plug-in rule for the Bartlett kernel.

    Parameters
    ----------
    scores : (N, p) per-sample score contributions.

    Returns
    -------
    The number of lags to include (at least 1, at most N // 4).
    """
    n = scores.shape[0]
    x, y = scores[:-1], scores[1:]
    denominator = np.einsum("tp,tp->p", x, x)  # sums without (N, p) temporaries
    usable = denominator > 0
    if n < 8 or not usable.any():
        return 1
    rho = np.clip(np.einsum("tp,tp->p", x, y)[usable] / denominator[usable], -0.99, 0.99)
    # AR(1) innovation variances
    innovation = y[:, usable] - rho * x[:, usable]
    sigma2 = np.einsum("tp,tp->p", innovation, innovation) / (n - 1)
    numerator = (4 * rho**2 * sigma2**2 / ((1 - rho) ** 6 * (1 + rho) ** 2)).sum()
    scale = (sigma2**2 / (1 - rho) ** 4).sum()
    alpha = numerator / scale if scale > 0 else 0.0
    lags = int(np.ceil(1.1447 * (alpha * n) ** (1.0 / 3.0)))
    return int(np.clip(lags, 1, max(n // 4, 1)))


def fft_length(minimum: int) -> int:
    """The smallest ``2^a 3^b 5^c >= minimum``: FFTs of such lengths run fast (60,501 -> 60,750 runs in half the time
    of the next power of two, 131,072)."""
    best = 1 << max(int(minimum - 1).bit_length(), 0)
    odd = 1
    while odd < best:  # every 3^b 5^c below the power of two, each with the least power of two that reaches minimum
        factor = odd
        while factor < best:
            best = min(best, factor << max(int(-(-minimum // factor) - 1).bit_length(), 0))
            factor *= 3
        odd *= 5
    return best


def correlation_length(scores: np.ndarray, max_lag: int = 500) -> int:
    """First lag at which every score component's autocorrelation falls inside its noise band ``2/sqrt(N)``.

    Parameters
    ----------
    scores : (N, p) per-sample score contributions.
    max_lag : longest lag examined.

    Returns
    -------
    The lag (at least 1).
    """
    n = scores.shape[0]
    centred = scores - scores.mean(axis=0)
    variance = np.einsum("tp,tp->p", centred, centred)
    usable = variance > 0
    if n < 8 or not usable.any():
        return 1
    # Components as contiguous rows: the FFTs run a third faster along them than down the columns.
    rows = (centred[:, usable] / np.sqrt(variance[usable])).T.copy()
    last = min(max_lag, n // 4)
    # Zero padding to N + last makes the circular correlation the linear one up to that lag (2N doubles the cost).
    size = fft_length(n + last + 1)
    spectrum = np.fft.rfft(rows, size, axis=1)
    acf = np.fft.irfft(spectrum.real**2 + spectrum.imag**2, size, axis=1)[:, : last + 1]
    inside = (np.abs(acf) < 2.0 / np.sqrt(n)).all(axis=0)
    hits = np.flatnonzero(inside[1:])
    return int(hits[0] + 1) if hits.size else int(last)


def design_inverse(design: np.ndarray) -> np.ndarray:
    """``(A + P)^-1`` of a normal-equations matrix (p, p), inverted with its rows and columns scaled to a unit
    diagonal.

    The parameters span decades of units (kg m, N m, kg m^2, N m per rad^3): unscaled, a nearly confounded
    direction takes the matrix's condition past ``1 / (p eps)`` and a pseudo-inverse drops it, giving it a variance
    of 0 (a static moment confounded with a cubic passive curve got std 0.008 kg m where its scaled inverse says
    26). Scaled, the condition is the squared column-scaled one the validity checks judge (1e16 at their limit).
    """
    scale = np.sqrt(np.clip(np.diag(design), 0.0, None))
    scale[scale == 0] = 1.0
    outer = np.outer(scale, scale)
    return np.asarray(np.linalg.pinv(design / outer, hermitian=True) / outer)


def hac_covariance(design: np.ndarray, scores: np.ndarray, lags: int | None = None) -> tuple[np.ndarray, int]:
    """Sandwich covariance ``A^-1 S A^-1`` with a Bartlett-weighted long-run score covariance ``S``.

    Parameters
    ----------
    design : (p, p) ``A = X^T W X`` of the weighted problem.
    scores : (N, p) per-sample scores ``sum_i x_ti w_i r_ti`` (summed over the joints of sample t, which
        also captures correlation between joints).
    lags : lag truncation; chosen from the data when None.

    Returns
    -------
    covariance : (p, p).
    lags : the truncation used.
    """
    if lags is None:
        # The AR(1) plug-in rule under-covers the smooth, filtered marker errors; twice the observed
        # correlation length keeps the Bartlett weights near 1 where the correlation really is.
        lags = max(bartlett_bandwidth(scores), 2 * correlation_length(scores))
        lags = min(lags, max(scores.shape[0] // 4, 1))
    long_run = bartlett_long_run(scores - scores.mean(axis=0), lags)
    inverse = design_inverse(design)
    covariance = inverse @ long_run @ inverse
    return 0.5 * (covariance + covariance.T), lags


def bartlett_long_run(centred: np.ndarray, lags: int) -> np.ndarray:
    """``Gamma_0 + sum_{l=1..L} (1 - l / (L + 1)) (Gamma_l + Gamma_l^T)`` with ``Gamma_l = sum_t x_t x_{t+l}^T``.

    Computed as ``S^T S / (L + 1)`` where the rows of ``S`` are the sums of ``L + 1`` consecutive scores
    (zero-padded at both ends): each pair of samples ``l <= L`` apart appears in ``L + 1 - l`` of those
    sums, which is exactly the Bartlett weight. O(N p^2) whatever the lag, where the sum over lags is
    O(L N p^2): at 200 Hz the lag reaches hundreds of samples.

    Parameters
    ----------
    centred : (N, p) centred scores.
    lags : Bartlett truncation L >= 0.

    Returns
    -------
    (p, p) long-run covariance (unnormalised, like the Gamma_l).
    """
    n, p = centred.shape
    padded = np.concatenate((np.zeros((lags + 1, p)), centred, np.zeros((lags, p))))
    cumulative = np.cumsum(padded, axis=0)
    sums = cumulative[lags + 1 :] - cumulative[: n + lags]
    return np.asarray(sums.T @ sums / (lags + 1.0))


def correlation_from_covariance(covariance: np.ndarray) -> np.ndarray:
    """(p, p) correlation matrix; a parameter with zero variance gets correlation 0 (not NaN)."""
    variances = np.diag(covariance)
    return np.asarray(covariance / np.sqrt(np.outer(variances, variances) + 1e-300))
