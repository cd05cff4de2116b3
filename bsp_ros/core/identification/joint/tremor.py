"""Tremor: an oscillation at 3-12 Hz in the joint torques and angles, measured, taken out of the fit and reported.

Parkinsonian rest tremor lies at 4-6 Hz, essential tremor at 4-12 Hz (Deuschl et al. 1998; Elble 2013: wrist
tremor of 0.1-1 Nm). A robot moving the arm at a few hundredths of a radian per second excites nothing there, so
torque in that band is the patient's, not the arm's segment parameters: it averages out of a quasi-static fit but
inflates its residual, and where it shakes the joints (through a compliant grip) it dithers their friction, which
then shows less than the relaxed arm has.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["TREMOR_BAND_HZ", "Tremor", "band_stopped", "tremor_in"]

# The band tremor lies in, Hz.
TREMOR_BAND_HZ = (3.0, 12.0)

# Power about the band's peak over what the band's median bin would put there: below this, no tremor.
MIN_BAND_RATIO = 20.0

# A tremor's peak spans this either side of its frequency, Hz (its frequency wanders; the window leaks).
PEAK_HALF_WIDTH_HZ = 0.5

# Segments of the averaged periodogram, s: a 4-6 Hz tremor's frequency to a quarter hertz.
SEGMENT_S = 4.0


@dataclass(frozen=True, kw_only=True)
class Tremor:
    """An oscillation in the tremor band of some series (one per column).

    Attributes
    ----------
    frequency_hz : the band's peak frequency over every column, Hz (NaN without tremor).
    rms : (k,) each column's RMS about the peak, the series' unit.
    ratio : (k,) each column's power about the peak over what the band's median bin would put there.
    """

    frequency_hz: float
    rms: np.ndarray
    ratio: np.ndarray

    @property
    def present(self) -> np.ndarray:
        """(k,) the columns with tremor."""
        return np.asarray(self.ratio > MIN_BAND_RATIO)


def _detrended(values: np.ndarray) -> np.ndarray:
    """``values`` (N, k) less each column's least-squares line: a slow motion leaks nothing into the band."""
    x = np.linspace(-1.0, 1.0, values.shape[0])
    design = np.column_stack((np.ones_like(x), x))
    coefficients, *_ = np.linalg.lstsq(design, values, rcond=None)
    return values - design @ coefficients


def _spectrum(values: np.ndarray, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """The averaged Hann periodogram (Welch, half-overlapping segments) of each column of ``values`` (N, k):
    frequencies (F,), Hz, and power per bin (F, k), the unit squared (the bins of a band sum to its variance)."""
    length = max(16, round(SEGMENT_S * rate_hz))
    length = min(length, values.shape[0])
    window = np.hanning(length)
    starts = range(0, values.shape[0] - length + 1, max(1, length // 2))
    total = np.zeros((length // 2 + 1, values.shape[1]))
    for start in starts:
        segment = _detrended(values[start : start + length])
        total += np.abs(np.fft.rfft(segment * window[:, None], axis=0)) ** 2
    power = total / len(starts) / (window**2).sum() / (length / 2)
    return np.fft.rfftfreq(length, 1.0 / rate_hz), power


def tremor_in(values: np.ndarray, rate_hz: float) -> Tremor:
    """The tremor in each column of ``values`` (N, k; finite, evenly sampled at ``rate_hz``): a narrow peak in the
    tremor band's spectrum.

    A tremor is an oscillation at one frequency: its power stands in a few bins (``PEAK_HALF_WIDTH_HZ`` about the
    band's peak), far above the band's median bin. A slow motion's leakage or a coloured noise falls smoothly
    across the band and puts no such peak there.
    """
    k = values.shape[1]
    if rate_hz < 2.2 * TREMOR_BAND_HZ[1] or values.shape[0] < 2 * SEGMENT_S * rate_hz:
        return Tremor(frequency_hz=float("nan"), rms=np.zeros(k), ratio=np.zeros(k))
    frequency, power = _spectrum(values, rate_hz)
    band = (frequency >= TREMOR_BAND_HZ[0]) & (frequency <= TREMOR_BAND_HZ[1])
    in_band, band_power = frequency[band], power[band]
    peak = in_band[int(np.argmax(band_power.sum(axis=1)))]
    near = np.abs(in_band - peak) <= PEAK_HALF_WIDTH_HZ
    peak_power = band_power[near].sum(axis=0)
    background = np.median(band_power, axis=0) * near.sum()
    ratio = peak_power / np.maximum(background, 1e-300)
    # A peak stands above the spectrum a hertz either side of it, inside the band or not: a slow motion's leakage
    # is largest at the band's lower edge and larger still below it.
    beside = (np.abs(frequency - peak) > 2 * PEAK_HALF_WIDTH_HZ) & (np.abs(frequency - peak) <= 4 * PEAK_HALF_WIDTH_HZ)
    ratio = np.where(power[band][near].max(axis=0) > power[beside].max(axis=0), ratio, 0.0)
    return Tremor(frequency_hz=float(peak), rms=np.sqrt(peak_power), ratio=ratio)


def band_stopped(values: np.ndarray, rate_hz: float, columns: np.ndarray) -> np.ndarray:
    """``values`` (N, k) with the tremor band taken out of the chosen ``columns`` (k,) bool (zero-phase, FFT).

    The band's content is taken from the series less the line through its ends, so that the jump a circular
    transform sees between its last and first sample puts nothing into the band.
    """
    out = values.copy()
    if not columns.any():
        return out
    chosen = values[:, columns]
    ramp = np.linspace(0.0, 1.0, values.shape[0])[:, None]
    ends = chosen[:1] + ramp * (chosen[-1:] - chosen[:1])
    spectrum = np.fft.rfft(chosen - ends, axis=0)
    frequency = np.fft.rfftfreq(values.shape[0], 1.0 / rate_hz)
    spectrum[(frequency < TREMOR_BAND_HZ[0]) | (frequency > TREMOR_BAND_HZ[1])] = 0.0
    out[:, columns] = chosen - np.fft.irfft(spectrum, n=values.shape[0], axis=0)
    return out
