"""Stretches of a session where the arm was not relaxed: torque the relaxed-arm model cannot explain, in bursts.

A patient's arm on a rehabilitation robot is rarely relaxed throughout: stroke patients have bursts of
involuntary activity (associated reactions, spasms; Dewald and Beer 2001 measure involuntary shoulder and elbow
torques of 5-20 % of the gravity torque). Such a burst is a joint torque that rises and falls over a few tenths
of a second to a few seconds (its content below ~2 Hz), at a time, not at a state: the arm at the same angles and
direction of motion at other times of the session shows no such torque. The model's own shortfalls (friction's
shape at a reversal, an elastic term it lacks, placement) are the opposite: they recur wherever the arm is in
that state. So each joint's residual, averaged over short bins, is compared with the residual of the same joint
at the nearest states at other times; what stands far above that comparison for long enough is activity.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.core.identification.robust import robust_sd

__all__ = ["Activity", "ActivitySettings", "active_stretches"]


@dataclass(frozen=True, kw_only=True)
class ActivitySettings:
    """How activity is told from the relaxed arm.

    Attributes
    ----------
    bin_s : residuals are averaged over bins of this length, s (sensor noise falls, a burst's content stays).
    threshold_sd : a bin whose torque the state does not explain lies this many robust sd of such torques off.
    min_duration_s : a stretch shorter than this is noise or a glitch (left to the outlier step), not activity.
    join_s : flagged bins closer than this are one stretch, s.
    margin_s : each stretch is widened by this at both ends (a burst's rise and fall below the threshold), s.
    exclude_s : neighbours in state closer in time than this do not count (a burst would explain itself), s.
    neighbours : states compared per bin.
    drift_s : what the state leaves unexplained, averaged over this long, is a drift (the drift check's), not a
        burst, s.
    max_active_share : more of the session active than this, and too little is left to call the arm relaxed.
    """

    bin_s: float = 0.1
    threshold_sd: float = 6.0
    min_duration_s: float = 0.3
    join_s: float = 0.3
    margin_s: float = 0.25
    exclude_s: float = 2.0
    neighbours: int = 24
    drift_s: float = 20.0
    max_active_share: float = 0.5


@dataclass(frozen=True, kw_only=True)
class Activity:
    """The stretches of a session where the arm was active.

    Attributes
    ----------
    active : (N,) samples inside an active stretch (margins included).
    spans_s : each stretch's start and end, s since the first sample.
    peak_nm : (n,) per joint, the largest unexplained bin torque inside the stretches, Nm (0 without any).
    """

    active: np.ndarray
    spans_s: tuple[tuple[float, float], ...]
    peak_nm: np.ndarray

    @property
    def share(self) -> float:
        """The share of samples inside the stretches."""
        return float(self.active.mean()) if self.active.size else 0.0

    @property
    def active_s(self) -> float:
        """The stretches' total length, s."""
        return float(sum(end - start for start, end in self.spans_s))


def _binned(values: np.ndarray, bins: np.ndarray, n_bins: int) -> np.ndarray:
    """(n_bins, k) the NaN-aware mean of ``values`` (N, k) in each bin (NaN where a bin holds no finite value)."""
    out = np.full((n_bins, values.shape[1]), np.nan)
    for column in range(values.shape[1]):
        finite = np.isfinite(values[:, column])
        counts = np.bincount(bins[finite], minlength=n_bins)
        sums = np.bincount(bins[finite], values[finite, column], minlength=n_bins)
        out[counts > 0, column] = sums[counts > 0] / counts[counts > 0]
    return out


# Queries per block of the brute-force neighbour search: bounds its memory to this times the pool (floats).
_BLOCK = 256

# At most this many bins: a long session's bins grow instead (the neighbour search is quadratic in them).
MAX_BINS = 2400


def _nearest(queries: np.ndarray, pool: np.ndarray, k: int) -> np.ndarray:
    """(Q, k) indices into ``pool`` (P, d) of each query's (Q, d) ``k`` nearest points, nearest first."""
    out = np.empty((queries.shape[0], k), dtype=np.int64)
    pool_sq = (pool**2).sum(axis=1)
    for start in range(0, queries.shape[0], _BLOCK):
        block = queries[start : start + _BLOCK]
        distance = pool_sq[None, :] - 2.0 * block @ pool.T
        part = (
            np.argpartition(distance, k - 1, axis=1)[:, :k]
            if k < pool.shape[0]
            else np.tile(np.arange(pool.shape[0]), (block.shape[0], 1))
        )
        order = np.argsort(np.take_along_axis(distance, part, axis=1), axis=1)
        out[start : start + block.shape[0]] = np.take_along_axis(part, order, axis=1)
    return out


def _neighbours(state: np.ndarray, valid: np.ndarray, k: int) -> np.ndarray | None:
    """(B, k) each bin's ``k`` nearest valid bins in ``state`` (B, d; its last column the direction of motion,
    which neighbours share), nearest first; None where a direction has fewer than ``k`` valid bins. Searched
    within each direction apart: half the pool each."""
    index = np.zeros((state.shape[0], k), dtype=np.int64)
    for direction in np.unique(state[valid, -1]):
        pool = np.flatnonzero(valid & (state[:, -1] == direction))
        if pool.size < k:
            return None
        queries = np.flatnonzero(state[:, -1] == direction)
        index[queries] = pool[_nearest(state[queries, :-1], state[pool, :-1], k)]
    return index


def _row_nanmedian(values: np.ndarray) -> np.ndarray:
    """(R,) the median of each row's finite values (NaN where a row has none): ``np.nanmedian`` without its masked
    arrays, by sorting (NaN sorts last) and taking the middle of each row's finite count."""
    ordered = np.sort(values, axis=1)
    count = np.isfinite(ordered).sum(axis=1)
    low = np.clip((count - 1) // 2, 0, None)[:, None]
    high = np.clip(count // 2, 0, values.shape[1] - 1)[:, None]
    middle = 0.5 * (np.take_along_axis(ordered, low, axis=1) + np.take_along_axis(ordered, high, axis=1))[:, 0]
    return np.where(count > 0, middle, np.nan)


def _state_explained(
    times_s: np.ndarray, index: np.ndarray, residual: np.ndarray, trusted: np.ndarray, settings: ActivitySettings
) -> np.ndarray:
    """(B,) the median residual of the ``trusted`` bins nearest in state at other times, from each bin's
    neighbours ``index`` (B, K; nearest first); NaN where too few such bins exist (the motion never came back)."""
    usable = trusted[index] & np.isfinite(residual[index])
    usable &= np.abs(times_s[index] - times_s[:, None]) > settings.exclude_s
    # the nearest usable ones, in order of distance
    chosen = usable & (np.cumsum(usable, axis=1) <= settings.neighbours)
    out = _row_nanmedian(np.where(chosen, residual[index], np.nan))
    return np.where(usable.sum(axis=1) >= settings.neighbours // 3, out, np.nan)


def _stretches(flag: np.ndarray, bin_s: float, settings: ActivitySettings) -> list[tuple[int, int]]:
    """The runs of flagged bins (joined across short gaps) lasting at least ``min_duration_s``: [start, end)."""
    runs: list[list[int]] = []
    join = max(1, round(settings.join_s / bin_s))
    for b in np.flatnonzero(flag):
        if runs and b - runs[-1][1] <= join:
            runs[-1][1] = int(b) + 1
        else:
            runs.append([int(b), int(b) + 1])
    min_bins = settings.min_duration_s / bin_s
    return [(a, b) for a, b in runs if b - a >= min_bins]


def _slow(values: np.ndarray, width: int) -> np.ndarray:
    """(B,) a drift under ``values`` (B,): the running median over ``width`` bins of medians over blocks of a
    tenth of it. A median, so that bursts covering up to half of any stretch do not move it."""
    block = max(1, width // 10)
    n_blocks = -(-values.size // block)
    padded = np.full(n_blocks * block, np.nan)
    padded[: values.size] = values
    with np.errstate(all="ignore"):
        blocks = _row_nanmedian(padded.reshape(n_blocks, block))
        half = min(5, blocks.size - 1)
        # Odd reflection at both ends: a linear drift runs on through the edge instead of bending there.
        before, after = 2 * blocks[0] - blocks[half:0:-1], 2 * blocks[-1] - blocks[-2 : -half - 2 : -1]
        edged = np.concatenate((before, blocks, after))
        windows = np.lib.stride_tricks.sliding_window_view(edged, 2 * half + 1)
        drift = np.nan_to_num(_row_nanmedian(windows))
    return np.repeat(drift, block)[: values.size]


@dataclass(frozen=True, kw_only=True)
class _Bins:
    """A session averaged over short bins."""

    times_s: np.ndarray
    bin_s: float
    residual: np.ndarray
    q: np.ndarray
    v: np.ndarray


def _joint_off(bins: _Bins, j: int, floor_nm: float, settings: ActivitySettings) -> tuple[np.ndarray, np.ndarray]:
    """(B,) joint ``j``'s binned residual less what its state explains and less its drift, and (B,) where that
    stands beyond the threshold."""
    span = np.maximum(np.nanmax(bins.q, axis=0) - np.nanmin(bins.q, axis=0), 1e-6)
    # Angles scaled by their range; the joint's direction of motion apart (friction turns with it).
    state = np.column_stack((bins.q / span, 10.0 * np.sign(np.nan_to_num(bins.v[:, j]))))
    valid = np.isfinite(state).all(axis=1)
    state = np.where(valid[:, None], state, 1e6)
    index = _neighbours(state, valid, 6 * settings.neighbours)
    if index is None:
        return np.full(valid.size, np.nan), np.zeros(valid.size, dtype=bool)
    drift_bins = round(settings.drift_s / bins.bin_s)
    # A drift first: the same state at another time would otherwise carry another drift into the comparison.
    residual = bins.residual[:, j] - _slow(bins.residual[:, j], drift_bins)
    # Twice: the second comparison leaves out the bins the first found far off (a long burst's own neighbours).
    trusted = valid.copy()
    for _ in range(2):
        off = residual - _state_explained(bins.times_s, index, residual, trusted, settings)
        off = off - _slow(off, drift_bins)
        scale = float(robust_sd(off[np.isfinite(off)])) if np.isfinite(off).sum() > 10 else np.inf
        far = np.abs(np.nan_to_num(off)) > max(settings.threshold_sd * scale, floor_nm)
        trusted = valid & ~far
    return off, far


def active_stretches(
    t_ns: np.ndarray,
    q_rad: np.ndarray,
    velocity_rad_s: np.ndarray,
    residual_nm: np.ndarray,
    floor_nm: np.ndarray,
    settings: ActivitySettings | None = None,
) -> Activity:
    """The stretches of a session where torque the relaxed-arm model cannot explain comes in bursts.

    Parameters
    ----------
    t_ns : (N,) sample stamps, ns.
    q_rad, velocity_rad_s : (N, n) joint angles, rad, and direction-of-motion velocities, rad/s.
    residual_nm : (N, n) the fit's torque residual, Nm; NaN where a joint's row was not used.
    floor_nm : (n,) torques below this never count as activity (what the sensor resolves), Nm.
    settings : thresholds (:class:`ActivitySettings`).

    Returns
    -------
    Activity; no stretch where the session is too short to compare states at different times.
    """
    settings = settings or ActivitySettings()
    n_samples, n = residual_nm.shape
    none = Activity(active=np.zeros(n_samples, dtype=bool), spans_s=(), peak_nm=np.zeros(n))
    t_s = (t_ns - t_ns[0]) * 1e-9
    if n_samples < 3 or t_s[-1] < 4 * settings.exclude_s:
        return none
    bin_s = max(settings.bin_s, t_s[-1] / MAX_BINS)
    index = np.floor(t_s / bin_s).astype(np.int64)
    n_bins = int(index[-1]) + 1
    bins = _Bins(
        times_s=(np.arange(n_bins) + 0.5) * bin_s,
        bin_s=bin_s,
        residual=_binned(residual_nm, index, n_bins),
        q=_binned(q_rad, index, n_bins),
        v=_binned(velocity_rad_s, index, n_bins),
    )
    off = np.full((n_bins, n), np.nan)
    flag = np.zeros(n_bins, dtype=bool)
    for j in range(n):
        off[:, j], far = _joint_off(bins, j, float(floor_nm[j]), settings)
        flag |= far
    runs = _stretches(flag, bin_s, settings)
    if not runs:
        return none
    margin = settings.margin_s
    spans = tuple((max(0.0, a * bin_s - margin), min(t_s[-1], b * bin_s + margin)) for a, b in runs)
    active = np.zeros(n_samples, dtype=bool)
    for start, end in spans:
        active |= (t_s >= start) & (t_s <= end)
    inside = np.zeros(n_bins, dtype=bool)
    for a, b in runs:
        inside[a:b] = True
    peak = np.nanmax(np.where(inside[:, None], np.abs(off), 0.0), axis=0)
    return Activity(active=active, spans_s=spans, peak_nm=np.nan_to_num(peak))
