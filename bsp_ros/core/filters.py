"""Butterworth low-pass sections and their zero-phase application, in numpy (no scipy import on the path)."""

from __future__ import annotations

import functools

import numpy as np

# scipy.signal gives the same numbers (tested to 1e-12), but importing it (and scipy.stats with it) or even
# scipy.linalg's banded solver would be a large share of `bsp identify`'s start (bench/README.md, `bsp identify`
# against `AnyReader`): the design and the zero-phase filter are a few lines of numpy each.

# Samples per block of the block recursion: its Toeplitz product costs BLOCK flops per sample, the state hand-over
# one Python step per block.
_BLOCK = 64


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


@functools.lru_cache(maxsize=64)
def _section_blocks(section: tuple[float, ...], block: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The block form of one transposed direct-form II section over ``block`` samples: ``y = T x + S z`` and the
    state after the block ``z' = U x + V z`` for a block's input ``x`` (block,) and its initial state ``z`` (2,).

    T is the lower-triangular Toeplitz matrix of the impulse response, S the responses to a unit initial state,
    U the states an impulse leaves at the block's end, V the state's own decay over the block: each from the
    section's recursion run once on unit inputs.
    """
    b0, b1, b2, _, a1, a2 = section

    def run(x: np.ndarray, z0: float, z1: float) -> tuple[np.ndarray, np.ndarray]:
        y, states = np.empty(x.size), np.empty((x.size, 2))
        for k, value in enumerate(x.tolist()):
            out = b0 * value + z0
            z0, z1 = b1 * value - a1 * out + z1, b2 * value - a2 * out
            y[k], states[k] = out, (z0, z1)
        return y, states

    impulse = np.zeros(block)
    impulse[0] = 1.0
    h, impulse_states = run(impulse, 0.0, 0.0)
    index = np.arange(block)
    lower = index[:, None] - index[None, :]
    toeplitz = np.where(lower >= 0, h[np.clip(lower, 0, None)], 0.0)
    zeros = np.zeros(block)
    from_z0, states_z0 = run(zeros, 1.0, 0.0)
    from_z1, states_z1 = run(zeros, 0.0, 1.0)
    state_response = np.column_stack((from_z0, from_z1))
    # An impulse at k has run block - 1 - k further steps at the block's end.
    end_states = impulse_states[block - 1 - index].T
    decay = np.column_stack((states_z0[-1], states_z1[-1]))
    return toeplitz, state_response, end_states, decay


def sosfilt(sos: np.ndarray, x: np.ndarray, zi: np.ndarray) -> np.ndarray:
    """Second-order sections along axis 0 with initial states, as ``scipy.signal.sosfilt(sos, x, axis=0, zi=zi)``.

    Each section runs as a block recursion: within blocks of 64 samples its output is the zero-state response (a
    Toeplitz product, one BLAS call for all blocks and channels) plus the response to the state the block starts
    in, those states from block to block by a prefix scan (log2 of the blocks' count in steps). The same filter
    as the sample recursion, to rounding.

    Parameters
    ----------
    sos : (S, 6) sections with a0 = 1.
    x : (N, ...) samples, N >= 2.
    zi : (S, 2, ...) initial states per section (transposed direct form II).
    """
    y = np.asarray(x, dtype=np.float64)
    shape = y.shape
    n = shape[0]
    block = _BLOCK
    count = -(-n // block)
    for section, state in zip(sos, zi, strict=True):
        toeplitz, state_response, end_states, decay = _section_blocks(tuple(float(c) for c in section), block)
        padded = np.zeros((count * block, int(np.prod(shape[1:], dtype=np.int64))))
        padded[:n] = y.reshape(n, -1)
        blocks = padded.reshape(count, block, -1)  # (blocks, block, channels)
        out = np.matmul(toeplitz, blocks)
        driven = np.matmul(end_states, blocks)  # (blocks, 2, channels): each block's input's share of its end state
        # The state each block starts in, z_k = V z_(k-1) + d_(k-1) from z_0, as a prefix scan in log2(blocks)
        # steps: after the step with shift s, each entry holds its last 2 s terms, sum_i V^(k - i) e_i.
        starts = np.empty((count, 2, blocks.shape[2]))
        starts[0] = np.asarray(state, dtype=np.float64).reshape(2, -1)
        starts[1:] = driven[:-1]
        power, shift = decay, 1
        while shift < count:
            starts[shift:] = starts[shift:] + np.matmul(power, starts[:-shift])
            power, shift = power @ power, 2 * shift
        out += np.matmul(state_response, starts)
        y = out.reshape(count * block, *shape[1:])[:n]
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
