"""Model check: the residual of each joint against the sensor noise the data shows."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.robust import high_frequency_sd
from bsp_ros.core.identification.stacked import Fit


def misfit_against_noise(fit: Fit, residual: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Per joint: the sensor noise the data shows (Nm) and the residual RMS as a multiple of it.

    ``residual`` (N, n), if given, is the one judged (e.g. less what marker placement explains); the noise is
    always the fit's own."""
    noise = high_frequency_sd(fit.residual)
    judged = fit.residual if residual is None else residual
    rms = np.sqrt(np.nanmean(judged**2, axis=0))
    return noise, rms / np.maximum(noise, 1e-12)
