"""Whether a session's EMG envelopes can tell when the arm was active: their samples checked before any rule reads
them (an envelope is finite and non-negative, its channels do not change, it is fast and long enough)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.streams import EmgSeries

__all__ = ["MAX_BAD_SHARE", "MIN_DURATION_S", "MIN_RATE_HZ", "EmgCheck", "EmgProblem", "check_emg", "combined_emg"]

# Samples with a non-finite or negative value are left out up to this share; beyond it the stream is not an
# envelope (a disconnected lead, raw EMG sent instead of its envelope) and tells nothing.
MAX_BAD_SHARE = 0.05

# Below this rate a 100 ms stretch above the threshold is two samples or fewer: no rule of duration holds, Hz.
MIN_RATE_HZ = 20.0

# The quiet baseline is the quietest 30 % of 2 s windows: under this a channel has too few of them, s.
MIN_DURATION_S = 20.0


class EmgProblem(StrEnum):
    """Why an EMG stream was not used."""

    NO_CHANNELS = "no_channels"
    CHANNELS_CHANGE = "channels_change"
    NON_FINITE = "non_finite"
    NEGATIVE = "negative"
    TOO_SLOW = "too_slow"
    TOO_SHORT = "too_short"


@dataclass(frozen=True, kw_only=True)
class EmgCheck:
    """An EMG stream as the activity rule may read it, or why it may not.

    Attributes
    ----------
    series : the usable samples (in time order, one per stamp, finite and non-negative), None where the stream is
        unusable.
    finding : ``emg_unusable`` with its :class:`EmgProblem` and numbers where the stream is unusable, else None.
    dropped : samples left out (non-finite or negative values, repeated stamps).
    """

    series: EmgSeries | None
    finding: Finding | None
    dropped: int = 0


def _unusable(problem: EmgProblem, series: EmgSeries, **values: float) -> EmgCheck:
    finding = Finding(
        code=FindingCode.EMG_UNUSABLE,
        values={"problem": str(problem), "n_channels": len(series.channels), **values},
    )
    return EmgCheck(series=None, finding=finding)


def check_emg(series: EmgSeries) -> EmgCheck:
    """The usable part of ``series``, or the finding that says why none of it is.

    A sample with any non-finite or negative value, and a repeated stamp, is left out (an envelope is a rectified,
    smoothed amplitude: never below 0); beyond ``MAX_BAD_SHARE`` of such samples, messages with other channels than
    the first's, a rate below ``MIN_RATE_HZ`` or a span under ``MIN_DURATION_S`` the stream is unusable.
    """
    envelope = np.asarray(series.envelope, dtype=np.float64)
    n = int(np.asarray(series.t_ns).size)
    if not series.channels or envelope.ndim != 2 or envelope.shape != (n, len(series.channels)):
        return _unusable(EmgProblem.NO_CHANNELS, series)
    if series.other_layout:
        share = 100.0 * series.other_layout / (n + series.other_layout)
        return _unusable(EmgProblem.CHANNELS_CHANGE, series, other_percent=share, n_other=series.other_layout)
    finite = np.asarray(np.isfinite(envelope).all(axis=1))
    with np.errstate(invalid="ignore"):
        negative = np.asarray(finite & (envelope < 0.0).any(axis=1))
    for problem, bad in ((EmgProblem.NON_FINITE, ~finite), (EmgProblem.NEGATIVE, negative)):
        if n and bad.mean() > MAX_BAD_SHARE:
            return _unusable(problem, series, bad_percent=100.0 * float(bad.mean()))
    good = np.flatnonzero(finite & ~negative)
    order = good[np.argsort(np.asarray(series.t_ns, dtype=np.int64)[good], kind="stable")]
    t_ns = np.asarray(series.t_ns, dtype=np.int64)[order]
    unique = np.concatenate(([True], np.diff(t_ns) > 0))
    t_ns, envelope = t_ns[unique], envelope[order[unique]]
    duration_s = float(t_ns[-1] - t_ns[0]) * 1e-9 if t_ns.size > 1 else 0.0
    if duration_s < MIN_DURATION_S:
        return _unusable(EmgProblem.TOO_SHORT, series, duration_s=duration_s, min_s=MIN_DURATION_S)
    rate_hz = 1e9 / float(np.median(np.diff(t_ns)))
    if rate_hz < MIN_RATE_HZ:
        return _unusable(EmgProblem.TOO_SLOW, series, rate_hz=rate_hz, min_hz=MIN_RATE_HZ)
    usable = EmgSeries(t_ns=t_ns, envelope=envelope, channels=series.channels)
    return EmgCheck(series=usable, finding=None, dropped=n - int(t_ns.size))


def combined_emg(series: Sequence[EmgSeries | None]) -> EmgSeries | None:
    """Several recordings' EMG as one stream, in time order: only where every recording has EMG of the same
    channels (else None: a recording without it would read as relaxed throughout)."""
    present = [s for s in series if s is not None]
    if not series or len(present) < len(series) or any(s.channels != present[0].channels for s in present):
        return None
    t_ns = np.concatenate([s.t_ns for s in present])
    order = np.argsort(t_ns, kind="stable")
    envelope = np.concatenate([np.asarray(s.envelope, dtype=np.float64) for s in present])[order]
    other = sum(s.other_layout for s in present)
    return EmgSeries(t_ns=t_ns[order], envelope=envelope, channels=present[0].channels, other_layout=other)
