"""Model check: the residual of each joint against the sensor noise the data shows."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.robust import high_frequency_sd
from bsp_ros.core.identification.stacked import Fit


def misfit_against_noise(fit: Fit) -> tuple[np.ndarray, np.ndarray]:
    """Per joint: the sensor noise the data shows (Nm) and the residual RMS as a multiple of it."""
    noise = high_frequency_sd(fit.residual)
    rms = np.sqrt(np.nanmean(fit.residual**2, axis=0))
    return noise, rms / np.maximum(noise, 1e-12)
