"""The rate samples are identified at: a fast wrench stream averaged in blocks to at most about 100 Hz."""

from __future__ import annotations

import math

import numpy as np

# Offline identification runs at this rate or below, whatever the sensor's (100 Hz to 1 kHz and more in rehab
# cells). The model's torques change below 2 Hz and a block mean keeps a white noise's information about them,
# so the estimate is the same; the validity checks (noise from first differences, spike windows in samples,
# residual autocorrelation) were calibrated on 100 Hz sessions and judge every rate alike; and the cost no longer
# grows with the sensor's rate (bench/README.md, `bsp identify` against `AnyReader`).
# Not 50 Hz, as live: on the realism bench's 1 cm skin markers the checks then let two more wrong runs pass.
IDENTIFICATION_MAX_RATE_HZ = 100.0
# Streams up to this much faster than the limit are left alone: a 100 Hz sensor whose clock runs 1 % fast is
# not averaged in pairs.
_RATE_TOLERANCE = 0.05


def _median_period_ns(t_ns: np.ndarray) -> float:
    """The median sample period (ns) of increasing stamps; 0 for fewer than 2 or repeated stamps."""
    if t_ns.size < 2:
        return 0.0
    period_ns = float(np.median(np.diff(t_ns)))
    return period_ns if period_ns > 0 else 0.0


def block_size(t_ns: np.ndarray, max_rate_hz: float) -> int:
    """Samples per block that bring a stream of stamps ``t_ns`` (ns, increasing) to at most ``max_rate_hz``
    (within 5 %), from its median sample period; 1 when it is slow enough."""
    return _block(_median_period_ns(t_ns), max_rate_hz)


def _block(period_ns: float, max_rate_hz: float) -> int:
    """:func:`block_size` of a stream with this median sample period (ns; 0 when unknown)."""
    if period_ns == 0.0:
        return 1
    return max(1, math.ceil(1e9 / period_ns / max_rate_hz - _RATE_TOLERANCE))


def block_means(t_ns: np.ndarray, values: np.ndarray, max_rate_hz: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Means of the samples in consecutive time bins of ``block_size`` sample periods, counted back from the
    newest stamp (whose bin is whole); a gap in the stream ends a bin rather than averaging across it.

    Parameters
    ----------
    t_ns : (N,) increasing stamps (ns).
    values : (N, k) samples.
    max_rate_hz : the highest rate wanted (Hz).

    Returns
    -------
    stamps : (M,) int64 mean stamp of each bin.
    means : (M, k) mean of each bin.
    counts : (M,) samples in each bin. The inputs unchanged (counts of 1) when already slow enough.
    """
    sample_ns = _median_period_ns(t_ns)
    block = _block(sample_ns, max_rate_hz)
    if block <= 1:
        return t_ns, values, np.ones(t_ns.size, dtype=np.int64)
    period_ns = block * sample_ns
    age = (t_ns[-1] - t_ns).astype(np.float64)
    bins = np.floor(age / period_ns + 1e-9).astype(np.int64)  # non-increasing along the stream
    starts = np.concatenate(([0], np.flatnonzero(np.diff(bins)) + 1))
    counts = np.diff(np.append(starts, t_ns.size))
    offsets = (t_ns - t_ns[starts[0]]).astype(np.float64)
    stamps = t_ns[starts[0]] + np.round(np.add.reduceat(offsets, starts) / counts).astype(np.int64)
    means = np.add.reduceat(values, starts, axis=0) / counts[:, None]
    return stamps, means, counts


def identification_rate_hz(t_ns: np.ndarray) -> float:
    """The rate (Hz) of identification samples stamped ``t_ns``, from their median period; 0 for fewer than 2."""
    period_ns = _median_period_ns(t_ns)
    return round(1e9 / period_ns, 3) if period_ns > 0 else 0.0
