"""Marker streams cleaned: sorted, on a common grid, frames a rigid chain cannot make removed, segment lengths."""

from __future__ import annotations

import itertools

import numpy as np

from bsp_ros.core.identification.robust import hampel_outliers, robust_sd
from bsp_ros.core.joint_angles.config import KinematicsConfig
from bsp_ros.core.joint_angles.geometry import sagittal_from_world
from bsp_ros.core.streams import MarkerSeries, common_frames
from bsp_ros.errors import DataError, InputError


def clean_marker(name: str, series: MarkerSeries) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Sort by stamp, drop duplicate stamps and non-finite positions; say how many."""
    t_ns = np.asarray(series.t_ns, dtype=np.int64)
    position = np.asarray(series.position_m, dtype=np.float64)
    if position.ndim != 2 or position.shape[1] != 3 or position.shape[0] != t_ns.shape[0]:
        raise InputError(f"marker {name!r}: positions of shape {position.shape} do not match {t_ns.shape[0]} stamps")
    notes = []
    finite = np.asarray(np.isfinite(position).all(axis=1))
    if not finite.all():
        notes.append(f"marker {name}: {int((~finite).sum())} frames with non-finite positions removed")
    order = np.argsort(t_ns, kind="stable")
    steps = np.diff(t_ns)
    if steps.size and steps.min() < -1_000_000_000:
        raise DataError(
            f"marker {name}: stamps jump back by {-steps.min() / 1e9:.3f} s at frame {int(np.argmin(steps)) + 1} "
            "(a looped replay or a reset clock): split the recording"
        )
    if (steps < 0).any():
        notes.append(f"marker {name}: stamps out of order, sorted")
    t_sorted, keep_sorted = t_ns[order], finite[order]
    duplicate = np.concatenate(([False], np.diff(t_sorted) == 0))
    if duplicate.any():
        notes.append(f"marker {name}: {int(duplicate.sum())} duplicate stamps removed (first kept)")
    keep = keep_sorted & ~duplicate
    return t_sorted[keep], position[order][keep], notes


def grid_values(grid_ns: np.ndarray, t_ns: np.ndarray, values: np.ndarray, max_gap_ns: int) -> tuple[np.ndarray, int]:
    """Interpolate samples onto the grid; NaN inside gaps longer than ``max_gap_ns`` and outside the data."""
    out = np.full((grid_ns.size, values.shape[1]), np.nan)
    if t_ns.size < 2:
        return out, 0
    after = np.searchsorted(t_ns, grid_ns, side="left")
    inside = (after > 0) & (after < t_ns.size)
    exact = (after < t_ns.size) & (t_ns[np.minimum(after, t_ns.size - 1)] == grid_ns)
    gap = np.zeros(grid_ns.size, dtype=np.int64)
    gap[inside] = t_ns[after[inside]] - t_ns[after[inside] - 1]
    usable = exact | (inside & (gap <= max_gap_ns))
    # Time relative to the first sample keeps float64 interpolation exact to the nanosecond.
    t_rel = (t_ns - t_ns[0]).astype(np.float64)
    g_rel = (grid_ns - t_ns[0]).astype(np.float64)
    for axis in range(values.shape[1]):
        out[usable, axis] = np.interp(g_rel[usable], t_rel, values[:, axis])
    nominal = np.median(np.diff(t_ns)) if t_ns.size > 1 else 0
    bridged = int((usable & ~exact & (gap > 1.5 * nominal)).sum())
    return out, bridged


# Frames in the rolling median of a marker's positions: up to 4 consecutive bad frames are found.
_MARKER_WINDOW = 9


def _rigid_chain_outliers(
    cleaned: dict[str, tuple[np.ndarray, np.ndarray]], names: tuple[str, ...], config: KinematicsConfig
) -> dict[str, np.ndarray]:
    """Per marker, (M,) bool flags of frames inconsistent with a rigid chain moving slowly.

    A frame is flagged when the marker jumps away from the rolling median of its neighbouring frames (a
    jump no arm makes at rehabilitation speeds), or when a segment length in it is off the session's
    median length. A length error is blamed on the marker that all of its flagged segments share (the
    elbow when both upper arm and forearm are off), on both ends of a segment otherwise.
    """
    flags = {}
    for name in names:
        _, position = cleaned[name]
        flags[name] = hampel_outliers(position, _MARKER_WINDOW, config.outlier_sd, floor=1e-3)
    off: list[np.ndarray] = []  # per segment: stamps with a length off the median
    for proximal, distal in itertools.pairwise(names):
        t_a, p_a = cleaned[proximal]
        t_b, p_b = cleaned[distal]
        common, i_a, i_b = common_frames(t_a, t_b)
        distance = np.linalg.norm(sagittal_from_world(p_b[i_b]) - sagittal_from_world(p_a[i_a]), axis=1)
        error = np.abs(distance - np.median(distance)) if distance.size else distance
        limit = max(config.max_length_error_m, config.outlier_sd * float(robust_sd(distance)) if distance.size else 0.0)
        # A length error at a frame where an end already jumped is explained by that jump.
        jumped = np.concatenate((t_a[flags[proximal]], t_b[flags[distal]]))
        off.append(np.setdiff1d(common[error > limit], jumped))
    # A frame's set of off segments is explained by one marker when it is exactly that marker's segments
    # (both for an inner marker, the one for an end marker); otherwise both ends of each are dropped.
    off_sets: dict[int, set[int]] = {}
    for s, stamps in enumerate(off):
        for stamp in stamps.tolist():
            off_sets.setdefault(stamp, set()).add(s)
    adjacency = [{s for s in (k - 1, k) if 0 <= s < len(off)} for k in range(len(names))]
    blamed: dict[str, list[int]] = {name: [] for name in names}
    for stamp, segments in off_sets.items():
        culprits = [names[k] for k in range(len(names)) if adjacency[k] == segments]
        if not culprits:
            culprits = sorted({names[e] for s in segments for e in (s, s + 1)})
        for name in culprits:
            blamed[name].append(stamp)
    for name in names:
        flags[name] |= np.isin(cleaned[name][0], np.array(blamed[name], dtype=np.int64))
    return flags


def remove_chain_outliers(
    cleaned: dict[str, tuple[np.ndarray, np.ndarray]], names: tuple[str, ...], config: KinematicsConfig
) -> tuple[dict[str, int], list[str]]:
    """Remove (as if occluded) marker frames inconsistent with the rigid chain; counts and a warning."""
    flags = _rigid_chain_outliers(cleaned, names, config)
    counts = {name: int(flag.sum()) for name, flag in flags.items() if flag.any()}
    for name, flag in flags.items():
        t_ns, position = cleaned[name]
        cleaned[name] = (t_ns[~flag], position[~flag])
    if not counts:
        return {}, []
    total = sum(counts.values())
    where = ", ".join(f"{name} {count}" for name, count in counts.items()) if len(counts) > 1 else next(iter(counts))
    return counts, [
        f"removed {total} marker frame{'s' if total > 1 else ''} inconsistent with the rigid chain ({where}): "
        "a jump or segment-length change no arm makes; treated as occluded"
    ]


def segment_lengths(
    cleaned: dict[str, tuple[np.ndarray, np.ndarray]], names: tuple[str, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """Median sagittal distance between consecutive markers over frames where both were seen."""
    lengths, stds = [], []
    for proximal, distal in itertools.pairwise(names):
        t_a, p_a = cleaned[proximal]
        t_b, p_b = cleaned[distal]
        common, i_a, i_b = common_frames(t_a, t_b)
        if common.size < 3:
            raise DataError(f"markers {proximal} and {distal} are never seen together: no segment length")
        distance = np.linalg.norm(sagittal_from_world(p_b[i_b]) - sagittal_from_world(p_a[i_a]), axis=1)
        median = float(np.median(distance))
        robust_sd = 1.4826 * float(np.median(np.abs(distance - median)))
        lengths.append(median)
        # Standard error of a median: sqrt(pi/2) times that of a mean.
        stds.append(1.2533 * robust_sd / np.sqrt(distance.size))
    return np.array(lengths), np.array(stds)
