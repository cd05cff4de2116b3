"""Stretches of a session where EMG shows the arm's muscles active: the clinician's baseline-plus-k-sd rule.

Relaxation is instructed, not verified; where a cell records surface EMG envelopes, a muscle is active where its
envelope's mean over 100 ms stands above its quiet baseline by more than ``k`` standard deviations of that baseline
(Hodges and Bui, Electroencephalogr Clin Neurophysiol 101:511-519, 1996, compared thresholds of 1-3 sd beyond the
baseline's mean for the mean over 20-100 ms, against onsets an examiner read; here 3 sd over 100 ms, the strictest
of them), and stays there for 100 ms. Their trials lasted seconds; a session lasts minutes, and the stricter
choice keeps false alarms on a quiet envelope rare over it: a rectified white noise floor low-passed at 6 Hz
(second order, sampled at 100 Hz) gave 0.15 false stretches per 10 min over 3 channels with 1 s baseline windows and
0.05 with 2 s (20 seeded sessions); low-passed at 3 Hz, smoother, 10.6 and 4.6 (each leaves out about half a
second). The rule suits envelopes of 5 Hz or more.

A session has no quiet period set aside before a task, so the baseline is taken from the session itself: the
quietest 30 % of its 2 s windows (lowest mean). A patient judged relaxed enough for identification is quiet for at
least half the session (``ActivitySettings.max_active_share``), so its quietest 30 % lie inside the relaxed part;
the baseline's mean and sd are those windows' samples' (the classic mean + k sd, not a median: the quiet windows
hold no bursts to resist).

An active stretch is widened before its onset by ``lead_s`` (the electromechanical delay: a muscle's force follows
its EMG by 30-100 ms, Cavanagh and Komi, Eur J Appl Physiol 42:159-163, 1979; and the streams' relative timing)
and after its end by ``lag_s`` (the force of a contraction outlasts its EMG while the muscle relaxes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.core.emg import check_emg
from bsp_ros.core.findings import Finding
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.activity import Activity
from bsp_ros.core.streams import EmgSeries

__all__ = ["EmgActivity", "EmgEvidence", "EmgSettings", "emg_activity", "emg_evidence", "emg_values", "with_emg"]


@dataclass(frozen=True, kw_only=True)
class EmgSettings:
    """How EMG activity is told from the quiet baseline.

    Attributes
    ----------
    k_sd : active where the envelope's mean over ``min_active_s`` stands above the baseline's mean plus this many
        of its sd.
    window_s : the baseline is chosen among windows of this length, s.
    quiet_share : the share of windows, lowest mean first, the baseline is taken from.
    min_active_s : the envelope is averaged over this long, and a stretch above the threshold shorter than this is
        noise, s.
    bridge_s : stretches closer than this are one (a burst's envelope dips), s.
    lead_s : each stretch is widened by this before its onset, s.
    lag_s : each stretch is widened by this after its end, s.
    """

    k_sd: float = 3.0
    window_s: float = 2.0
    quiet_share: float = 0.3
    min_active_s: float = 0.1
    bridge_s: float = 0.1
    lead_s: float = 0.1
    lag_s: float = 0.3


@dataclass(frozen=True, kw_only=True)
class EmgActivity:
    """Where the EMG showed the arm active.

    Attributes
    ----------
    channels : (C,) the channels' names.
    baseline : (C,) each channel's quiet mean, in the envelope's unit.
    sd : (C,) each channel's quiet sd, in the envelope's unit.
    spans_ns : each active stretch's start and end (widened by ``lead_s`` and ``lag_s``), ns, in time order and
        disjoint.
    fired : the channels active somewhere, in channel order.
    k_sd : the threshold's sd multiple used.
    """

    channels: tuple[str, ...]
    baseline: np.ndarray
    sd: np.ndarray
    spans_ns: tuple[tuple[int, int], ...]
    fired: tuple[str, ...]
    k_sd: float

    def active_at(self, t_ns: np.ndarray) -> np.ndarray:
        """(N,) bool: the stamps ``t_ns`` (N,) inside an active stretch."""
        t = np.asarray(t_ns, dtype=np.int64)
        if not self.spans_ns:
            return np.zeros(t.size, dtype=bool)
        starts = np.array([a for a, _ in self.spans_ns], dtype=np.int64)
        ends = np.array([b for _, b in self.spans_ns], dtype=np.int64)
        at = np.searchsorted(starts, t, side="right") - 1
        return (at >= 0) & (t <= ends[np.clip(at, 0, None)])


def _quiet_baseline(t_s: np.ndarray, x: np.ndarray, settings: EmgSettings) -> tuple[float, float]:
    """The mean and sd of the samples of ``x`` (N,) in the quietest ``quiet_share`` of its ``window_s`` windows
    (those holding at least half the typical count of samples)."""
    window = np.floor(t_s / settings.window_s).astype(np.int64)
    counts = np.bincount(window)
    full = counts >= 0.5 * np.median(counts[counts > 0])
    means = np.bincount(window, x) / np.maximum(counts, 1)
    candidates = np.flatnonzero(full)
    n_quiet = max(3, int(np.ceil(settings.quiet_share * candidates.size)))
    quiet = candidates[np.argsort(means[candidates], kind="stable")[:n_quiet]]
    samples = x[np.isin(window, quiet)]
    return float(samples.mean()), float(samples.std(ddof=1))


def _moving_mean(x: np.ndarray, width: int) -> np.ndarray:
    """(N,) the mean of ``x`` (N,) over ``width`` samples centred on each (fewer at the ends)."""
    total = np.convolve(x, np.ones(width), mode="same")
    count = np.convolve(np.ones_like(x), np.ones(width), mode="same")
    return np.asarray(total / count)


def _runs(t_ns: np.ndarray, above: np.ndarray, dt_ns: int, settings: EmgSettings) -> list[tuple[int, int]]:
    """The stretches where ``above`` (N,) holds, [first stamp, last stamp + ``dt_ns``] in ns, joined across gaps
    under ``bridge_s`` and kept where they last ``min_active_s``."""
    edges = np.diff(np.concatenate(([0], above.astype(np.int8), [0])))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    runs: list[list[int]] = []
    for a, b in zip(t_ns[starts].tolist(), (t_ns[ends] + dt_ns).tolist(), strict=True):
        if runs and a - runs[-1][1] < settings.bridge_s * 1e9:
            runs[-1][1] = b
        else:
            runs.append([a, b])
    return [(a, b) for a, b in runs if b - a >= settings.min_active_s * 1e9 - 1]


def _union(spans: list[tuple[int, int]]) -> tuple[tuple[int, int], ...]:
    """Overlapping spans merged, in time order."""
    out: list[list[int]] = []
    for a, b in sorted(spans):
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        else:
            out.append([a, b])
    return tuple((a, b) for a, b in out)


def emg_activity(series: EmgSeries, settings: EmgSettings | None = None) -> EmgActivity:
    """Where the mean over ``min_active_s`` of any channel of ``series`` stood above its quiet baseline + ``k_sd``
    sd for ``min_active_s``.

    Parameters
    ----------
    series : usable envelopes (``bsp_ros.core.emg.check_emg``'s: in time order, finite, non-negative, at least
        20 s at 20 Hz or more).
    settings : the rule's constants (:class:`EmgSettings`).

    Returns
    -------
    EmgActivity: the union of every channel's stretches, widened.
    """
    settings = settings or EmgSettings()
    t_ns = np.asarray(series.t_ns, dtype=np.int64)
    t_s = (t_ns - t_ns[0]) * 1e-9
    dt_ns = int(np.median(np.diff(t_ns)))
    width = max(1, round(settings.min_active_s * 1e9 / dt_ns))
    n_channels = len(series.channels)
    baseline, sd = np.zeros(n_channels), np.zeros(n_channels)
    spans: list[tuple[int, int]] = []
    fired = []
    for c in range(n_channels):
        x = np.asarray(series.envelope[:, c], dtype=np.float64)
        baseline[c], sd[c] = _quiet_baseline(t_s, x, settings)
        runs = _runs(t_ns, _moving_mean(x, width) > baseline[c] + settings.k_sd * sd[c], dt_ns, settings)
        if runs:
            fired.append(series.channels[c])
        lead, lag = round(settings.lead_s * 1e9), round(settings.lag_s * 1e9)
        spans.extend((a - lead, b + lag) for a, b in runs)
    return EmgActivity(
        channels=series.channels,
        baseline=baseline,
        sd=sd,
        spans_ns=_union(spans),
        fired=tuple(fired),
        k_sd=settings.k_sd,
    )


def emg_values(torque_active: np.ndarray, emg_active: np.ndarray, activity: EmgActivity) -> dict[str, float | str]:
    """The ``arm_active`` finding's EMG numbers over a session's samples.

    Parameters
    ----------
    torque_active, emg_active : (N,) bool, the samples inside the torque's and the EMG's active stretches.
    activity : the EMG's stretches and channels.

    Returns
    -------
    ``emg_share_percent``, ``torque_share_percent``, ``confirmed_percent`` (of the torque's active samples, those
    the EMG shows active too; 0 without any), ``emg_only_percent`` (active by EMG alone), ``channels`` (those that
    fired, comma-joined) and ``k_sd``.
    """
    n = max(int(torque_active.size), 1)
    torque_n = int(torque_active.sum())
    both = int((torque_active & emg_active).sum())
    return {
        "emg_share_percent": 100.0 * float(emg_active.sum()) / n,
        "torque_share_percent": 100.0 * torque_n / n,
        "confirmed_percent": 100.0 * both / torque_n if torque_n else 0.0,
        "emg_only_percent": 100.0 * float((emg_active & ~torque_active).sum()) / n,
        "channels": ", ".join(activity.fired),
        "k_sd": activity.k_sd,
    }


@dataclass(frozen=True, kw_only=True)
class EmgEvidence:
    """What a session's EMG says about its identification samples.

    Attributes
    ----------
    activity : the EMG's stretches, None where the EMG was unusable.
    active : (N,) the identification samples inside them (all False without).
    notes : ``emg_unusable`` where the EMG could not be used.
    """

    activity: EmgActivity | None
    active: np.ndarray
    notes: tuple[Finding, ...] = ()


def emg_evidence(data: IdentificationData, settings: EmgSettings | None = None) -> EmgEvidence | None:
    """The EMG's stretches at ``data``'s samples (:func:`emg_activity` of the usable envelopes,
    :func:`bsp_ros.core.emg.check_emg`); None where the session has no EMG."""
    if data.emg is None:
        return None
    check = check_emg(data.emg)
    if check.series is None:
        notes = () if check.finding is None else (check.finding,)
        return EmgEvidence(activity=None, active=np.zeros(data.t_ns.size, dtype=bool), notes=notes)
    activity = emg_activity(check.series, settings)
    return EmgEvidence(activity=activity, active=activity.active_at(data.t_ns))


def with_emg(torque: Activity, evidence: EmgEvidence, t_ns: np.ndarray) -> Activity:
    """The union of the torque's stretches and the EMG's (:class:`Activity` over the samples ``t_ns`` (N,)): the
    samples active by either, their spans merged (s since the first sample), the torque's peaks."""
    if evidence.activity is None:
        return torque
    t0, end_s = int(t_ns[0]), float(t_ns[-1] - t_ns[0]) * 1e-9
    emg_spans = [
        (max(0.0, (a - t0) * 1e-9), min(end_s, (b - t0) * 1e-9))
        for a, b in evidence.activity.spans_ns
        if b >= t_ns[0] and a <= t_ns[-1]
    ]
    scale = 1_000_000_000
    merged = _union([(round(a * scale), round(b * scale)) for a, b in (*torque.spans_s, *emg_spans)])
    return Activity(
        active=torque.active | evidence.active,
        spans_s=tuple((a / scale, b / scale) for a, b in merged),
        peak_nm=torque.peak_nm,
    )
