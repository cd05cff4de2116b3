"""Butterworth low-pass sections and their zero-phase application, in numpy (no scipy.signal import on the path)."""

from __future__ import annotations

import functools

import numpy as np
from scipy.linalg import solve_banded

# scipy.signal gives the same numbers (tested to 1e-12), but importing it costs `bsp identify` about 0.4 s (it
# pulls in scipy.stats): the design and the zero-phase filter are a few lines each.


@functools.lru_cache(maxsize=64)
def butter_lowpass_sos(order: int, cutoff_hz: float, rate_hz: float) -> np.ndarray:
    """Digital Butterworth low-pass as second-order sections, as ``scipy.signal.butter(order, cutoff_hz,
    fs=rate_hz, output="sos")``: the analog prototype, pre-warped and mapped by the bilinear transform. The
    sections are scipy's for even orders; for odd ones scipy may pair the single zero with another section
    near the Nyquist frequency (the same filter).

    Parameters
    ----------
    order : filter order, >= 1.
    cutoff_hz : -3 dB frequency, 0 < cutoff_hz < rate_hz / 2 (Hz).
    rate_hz : sample rate (Hz).

    Returns
    -------
    (ceil(order / 2), 6) sections ``[b0, b1, b2, 1, a1, a2]``, the gain in the first; read-only (cached).
    """
    if order < 1 or not 0.0 < cutoff_hz < rate_hz / 2.0:
        raise ValueError(f"a Butterworth low-pass needs order >= 1 and 0 < cutoff < rate / 2, got {order}, {cutoff_hz}")
    m = np.arange(-order + 1, order, 2)
    analog = -np.exp(1j * np.pi * m / (2 * order)) * 4.0 * np.tan(np.pi * cutoff_hz / rate_hz)  # pre-warped, fs=2
    poles = (4.0 + analog) / (4.0 - analog)
    gain = float(np.real(np.prod(analog) / np.prod(analog - 4.0)))  # bilinear_zpk of the gain warped**order
    # Conjugate pairs (upper half plane), ordered as scipy's zpk2sos: the pole farthest from the unit circle first.
    upper = poles[poles.imag > 1e-14 * np.abs(poles)]
    upper = upper[np.argsort(np.abs(1.0 - np.abs(upper)))[::-1]]
    sections = [np.array([1.0, 2.0, 1.0, 1.0, -2.0 * p.real, abs(p) ** 2]) for p in upper]
    if order % 2:
        # The real pole first; the single zero goes with the last section, as scipy pairs them.
        real = float(poles[np.abs(poles.imag) <= 1e-14 * np.abs(poles)][0].real)
        sections.insert(0, np.array([1.0, 2.0, 1.0, 1.0, -real, 0.0]))
        sections[-1][:3] = [1.0, 1.0, 0.0]
    sos = np.array(sections)
    sos[0, :3] *= gain
    sos.flags.writeable = False
    return sos


def _section_zi(b: np.ndarray, a: np.ndarray) -> np.ndarray:
    """Steady-state state (2,) of one transposed direct-form II section for a unit step (``lfilter_zi``)."""
    i_minus_a = np.eye(2) - np.array([[-a[1], -a[2]], [1.0, 0.0]]).T
    return np.linalg.solve(i_minus_a, b[1:] - a[1:] * b[0])


def sosfilt(sos: np.ndarray, x: np.ndarray, zi: np.ndarray) -> np.ndarray:
    """Second-order sections along axis 0 with initial states, as ``scipy.signal.sosfilt(sos, x, axis=0, zi=zi)``.

    Each section's recursion ``y[n] + a1 y[n-1] + a2 y[n-2] = b0 x[n] + b1 x[n-1] + b2 x[n-2]`` is a banded
    lower-triangular system, solved in one LAPACK call; the initial states enter its first two rows.

    Parameters
    ----------
    sos : (S, 6) sections with a0 = 1.
    x : (N, ...) samples, N >= 2.
    zi : (S, 2, ...) initial states per section (transposed direct form II).
    """
    y = np.asarray(x, dtype=np.float64)
    n = y.shape[0]
    for section, state in zip(sos, zi, strict=True):
        b, a = section[:3], section[3:]
        rhs = b[0] * y
        rhs[1:] += b[1] * y[:-1]
        rhs[2:] += b[2] * y[:-2]
        rhs[0] += state[0]
        rhs[1] += state[1]
        banded = np.zeros((3, n))
        banded[0], banded[1], banded[2] = 1.0, a[1], a[2]
        y = solve_banded((2, 0), banded, rhs.reshape(n, -1), check_finite=False).reshape(y.shape)
    return y


def zero_phase_lowpass(values: np.ndarray, sos: np.ndarray, padlen: int) -> np.ndarray:
    """Sections run forwards and backwards along axis 0 (no phase lag), padded by odd extension, as
    ``scipy.signal.sosfiltfilt(sos, values, axis=0, padtype="odd", padlen=padlen)``.

    Parameters
    ----------
    values : (N, ...) samples; N > padlen.
    sos : (S, 6) sections (:func:`butter_lowpass_sos`).
    padlen : samples of odd extension at each end (0 <= padlen < N).
    """
    x = np.asarray(values, dtype=np.float64)
    if padlen:
        start = 2.0 * x[0] - x[padlen:0:-1]
        end = 2.0 * x[-1] - x[-2 : -padlen - 2 : -1]
        x = np.concatenate((start, x, end))
    zi = np.empty((len(sos), 2))
    scale = 1.0
    for k, section in enumerate(sos):
        zi[k] = scale * _section_zi(section[:3], section[3:])
        scale *= section[:3].sum() / section[3:].sum()
    shape = (len(sos), 2) + (1,) * (x.ndim - 1)
    y = sosfilt(sos, x, zi.reshape(shape) * x[0])
    y = sosfilt(sos, y[::-1], zi.reshape(shape) * y[-1])[::-1]
    return y[padlen : y.shape[0] - padlen] if padlen else y
