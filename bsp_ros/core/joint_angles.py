"""Joint angles, segment lengths and direction-of-motion velocities from motion-capture markers."""

from __future__ import annotations

import functools
import itertools
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from bsp_ros.core.filters import butter_lowpass_sos, zero_phase_lowpass
from bsp_ros.core.identification.robust import hampel_outliers, robust_sd
from bsp_ros.core.motion_band import config_for_motion
from bsp_ros.core.streams import MarkerSeries, markers_for
from bsp_ros.errors import DataError, InputError
from bsp_ros.validation import check_finite_scalar, check_positive


@dataclass(frozen=True)
class KinematicsConfig:
    """How marker trajectories become joint angles.

    Attributes
    ----------
    cutoff_hz : zero-phase low-pass cutoff for the angles (the method paper's 5 Hz).
    direction_cutoff_hz : far lower cutoff for the velocity whose sign gives the direction of motion;
        at 0.03 rad/s a 5 Hz-filtered derivative is as noisy as the signal (NOTES.md 1).
    max_gap_s : marker gaps up to this long are bridged by interpolation; longer ones remove samples.
    min_run_s : stretches of valid frames shorter than this are dropped (the filters need a run-in).
    max_length_error_m : a marker frame whose segment length is further than this (and than
        ``outlier_sd`` robust standard deviations) from the session's median length is removed.
    outlier_sd : a marker position further than this many robust standard deviations from the rolling
        median of its neighbours (a jump no arm makes) is removed, as is a joint angle in
        :func:`kinematics_from_angles`.
    dynamics_cutoff_hz : zero-phase low-pass cutoff of the angles whose derivatives give the velocities and
        accelerations of the inertial torques: twice differentiated, marker noise grows with the cutoff to
        the power 2.5, and an arm moved at rehabilitation speeds has no content above ~0.5 Hz.
    """

    cutoff_hz: float = 5.0
    direction_cutoff_hz: float = 0.5
    dynamics_cutoff_hz: float = 1.0
    max_gap_s: float = 0.1
    min_run_s: float = 2.0
    max_length_error_m: float = 0.005
    outlier_sd: float = 8.0

    def __post_init__(self) -> None:
        check_positive("cutoff_hz", self.cutoff_hz, 1000.0)
        check_positive("direction_cutoff_hz", self.direction_cutoff_hz, self.cutoff_hz)
        check_positive("dynamics_cutoff_hz", self.dynamics_cutoff_hz, 1000.0)
        check_finite_scalar("max_gap_s", self.max_gap_s, 0.0, 10.0)
        check_finite_scalar("min_run_s", self.min_run_s, 0.0, 600.0)
        check_positive("max_length_error_m", self.max_length_error_m, 1.0)
        check_positive("outlier_sd", self.outlier_sd, 1000.0)


@dataclass(frozen=True)
class MarkerKinematics:
    """Joint angles on a uniform marker-rate grid.

    Attributes
    ----------
    t_ns : (M,) int64 grid stamps (ns).
    q_rad : (M, n) low-pass filtered joint angles (rad); NaN where not valid.
    direction_velocity_rad_s : (M, n) heavily smoothed joint velocities (rad/s); NaN where not valid.
    lengths_m : (n,) segment lengths (m), medians over the session of the sagittal marker distances.
    lengths_std_m : (n,) standard errors of those lengths (m).
    n_frames_bridged : frames filled across short gaps, per marker.
    n_frames_invalid : grid frames without valid angles (long gaps, short runs, edges).
    n_frames_rejected : marker (or ``angles``) -> frames removed as inconsistent with the rigid chain.
    direction_velocity_noise_rad_s : (n,) standard deviation of the marker noise in the direction
        velocities (rad/s), propagated from the angle noise through the filter.
    warnings : plain-language notes on data quality.
    velocity_rad_s, acceleration_rad_s2 : (M, n) derivatives of the angles low-passed at
        ``dynamics_cutoff_hz`` (rad/s, rad/s^2), for the inertial torques; None when not computed.
    """

    t_ns: np.ndarray
    q_rad: np.ndarray
    direction_velocity_rad_s: np.ndarray
    lengths_m: np.ndarray
    lengths_std_m: np.ndarray
    n_frames_bridged: dict[str, int]
    n_frames_invalid: int
    direction_velocity_noise_rad_s: np.ndarray
    warnings: list[str] = field(default_factory=list)
    n_frames_rejected: dict[str, int] = field(default_factory=dict)
    velocity_rad_s: np.ndarray | None = None
    acceleration_rad_s2: np.ndarray | None = None

    @property
    def rate_hz(self) -> float:
        """Grid rate (Hz)."""
        return 1e9 / float(self.t_ns[1] - self.t_ns[0])


def sagittal_from_world(position_m: npt.ArrayLike) -> np.ndarray:
    """Project world positions onto the sagittal plane: (..., 3) ``[x, y, z]`` -> (..., 2) ``[y, z]``."""
    return np.asarray(position_m, dtype=np.float64)[..., 1:3]


def joint_angles_from_positions(points_yz: npt.ArrayLike) -> np.ndarray:
    """Joint angles of a planar chain from its joint and contact-point positions.

    Parameters
    ----------
    points_yz : (N, n + 1, 2) sagittal positions of shoulder, distal joints and contact point (m).

    Returns
    -------
    (N, n) ``q1`` absolute from +y, the others relative to the previous segment, in (-pi, pi] (rad).
    """
    points = np.asarray(points_yz, dtype=np.float64)
    step = np.diff(points, axis=1)
    phi = np.arctan2(step[..., 1], step[..., 0])
    relative = np.diff(phi, axis=1)
    relative = np.angle(np.exp(1j * relative))  # wrap to (-pi, pi]
    return np.concatenate((phi[:, :1], relative), axis=1)


def _clean_marker(name: str, series: MarkerSeries) -> tuple[np.ndarray, np.ndarray, list[str]]:
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


def _grid_values(grid_ns: np.ndarray, t_ns: np.ndarray, values: np.ndarray, max_gap_ns: int) -> tuple[np.ndarray, int]:
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


def _valid_runs(valid: np.ndarray) -> list[tuple[int, int]]:
    """Half-open index ranges of consecutive True values."""
    padded = np.concatenate(([False], valid, [False])).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _zero_phase_lowpass(values: np.ndarray, cutoff_hz: float, rate_hz: float, order: int) -> np.ndarray:
    """Butterworth low-pass run forwards and backwards (no phase lag), padded by odd extension.

    The pad is about three time constants long so that slopes at the run's ends are kept, which a short
    default pad does not do at 0.5 Hz.
    """
    nyquist = rate_hz / 2.0
    if cutoff_hz >= nyquist:
        return values.copy()
    padlen = min(values.shape[0] - 1, int(3.0 * rate_hz / cutoff_hz))
    return zero_phase_lowpass(values, butter_lowpass_sos(order, cutoff_hz, rate_hz), padlen)


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
        common, i_a, i_b = np.intersect1d(t_a, t_b, assume_unique=True, return_indices=True)
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


def _remove_chain_outliers(
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


def _segment_lengths(
    cleaned: dict[str, tuple[np.ndarray, np.ndarray]], names: tuple[str, ...]
) -> tuple[np.ndarray, np.ndarray]:
    """Median sagittal distance between consecutive markers over frames where both were seen."""
    lengths, stds = [], []
    for proximal, distal in itertools.pairwise(names):
        t_a, p_a = cleaned[proximal]
        t_b, p_b = cleaned[distal]
        common, i_a, i_b = np.intersect1d(t_a, t_b, assume_unique=True, return_indices=True)
        if common.size < 3:
            raise DataError(f"markers {proximal} and {distal} are never seen together: no segment length")
        distance = np.linalg.norm(sagittal_from_world(p_b[i_b]) - sagittal_from_world(p_a[i_a]), axis=1)
        median = float(np.median(distance))
        robust_sd = 1.4826 * float(np.median(np.abs(distance - median)))
        lengths.append(median)
        # Standard error of a median: sqrt(pi/2) times that of a mean.
        stds.append(1.2533 * robust_sd / np.sqrt(distance.size))
    return np.array(lengths), np.array(stds)


def _direction_velocity_noise(
    raw_q: np.ndarray, filtered_q: np.ndarray, config: KinematicsConfig, rate_hz: float
) -> np.ndarray:
    """Noise (1 sd, rad/s) of the direction velocity, from the angle noise seen above the angle cutoff.

    The raw-minus-filtered angle holds the white marker noise above ``cutoff_hz`` only, so its variance is
    scaled up by the share of the band it covers; the filter-and-differentiate chain is linear, so its
    noise gain is the norm of its impulse response.
    """
    high = raw_q - filtered_q
    high = high[np.isfinite(high).all(axis=1)]
    if high.shape[0] < 10:
        return np.full(raw_q.shape[1], np.nan)
    band_share = max(1.0 - 2.0 * config.cutoff_hz / rate_hz, 0.05)
    # The median absolute deviation: one glitched frame must not inflate the noise, hence the dead band.
    angle_sd = robust_sd(high, axis=0) / np.sqrt(band_share)
    return np.asarray(angle_sd * _direction_noise_gain(config.direction_cutoff_hz, rate_hz))


@functools.lru_cache(maxsize=64)
def _direction_noise_gain(direction_cutoff_hz: float, rate_hz: float) -> float:
    """Norm of the impulse response of filtering (zero phase) then differentiating, (rad/s) per rad."""
    length = int(20.0 * rate_hz / direction_cutoff_hz) | 1
    impulse = np.zeros((length, 1))
    impulse[length // 2] = 1.0
    response = np.gradient(_zero_phase_lowpass(impulse, direction_cutoff_hz, rate_hz, 2), 1.0 / rate_hz, axis=0)
    return float(np.linalg.norm(response))


def _filtered_runs(
    raw_q: np.ndarray, rate_hz: float, config: KinematicsConfig, angle_filter: bool = True, trim_edges: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """Zero-phase filtered angles and direction velocities over each long-enough run of valid frames.

    With ``trim_edges`` the direction velocity is left out (NaN) within a quarter period of its cutoff of
    each run's ends: there the padding makes it noise, and its sign, the direction of motion, a guess.

    Returns angles, velocities (NaN outside usable runs), the direction-velocity noise (n,), and notes.

    Raises
    ------
    DataError
        No run is long enough.
    """
    notes = []
    if angle_filter and config.cutoff_hz >= rate_hz / 2:
        notes.append(f"angle cutoff {config.cutoff_hz} Hz is above the Nyquist {rate_hz / 2:g} Hz: not filtered")
    valid = np.isfinite(raw_q).all(axis=1)
    q_rad = np.full_like(raw_q, np.nan)
    smooth = np.full_like(raw_q, np.nan)
    velocity = np.full_like(raw_q, np.nan)
    min_frames = max(int(config.min_run_s * rate_hz), 16)
    for begin, end in _valid_runs(valid):
        if end - begin < min_frames:
            continue
        run = np.unwrap(raw_q[begin:end], axis=0)
        smooth[begin:end] = _zero_phase_lowpass(run, config.cutoff_hz, rate_hz, order=4)
        q_rad[begin:end] = smooth[begin:end] if angle_filter else run
        slow = _zero_phase_lowpass(run, config.direction_cutoff_hz, rate_hz, order=2)
        velocity[begin:end] = np.gradient(slow, 1.0 / rate_hz, axis=0)
        if trim_edges:
            edge = min(int(0.25 * rate_hz / config.direction_cutoff_hz), (end - begin) // 4)
            velocity[begin : begin + edge] = np.nan
            velocity[end - edge : end] = np.nan
    if not np.isfinite(q_rad).any():
        raise DataError("no stretch of marker data is long enough to give joint angles")
    # The noise is judged against the smoothed angles even when those are not returned.
    noise = _direction_velocity_noise(raw_q, smooth, config, rate_hz)
    return q_rad, velocity, noise, notes


def _motion_runs(
    raw_q: np.ndarray, valid_q: np.ndarray, rate_hz: float, cutoff_hz: float
) -> tuple[np.ndarray, np.ndarray]:
    """Velocities and accelerations (rad/s, rad/s^2) of the angles low-passed at ``cutoff_hz`` (zero phase), over
    each run where ``valid_q`` (the usable angles) is finite; NaN elsewhere."""
    velocity = np.full_like(raw_q, np.nan)
    acceleration = np.full_like(raw_q, np.nan)
    for begin, end in _valid_runs(np.isfinite(valid_q).all(axis=1)):
        if end - begin < 16:
            continue
        run = np.unwrap(raw_q[begin:end], axis=0)
        smooth = _zero_phase_lowpass(run, cutoff_hz, rate_hz, order=4)
        velocity[begin:end] = np.gradient(smooth, 1.0 / rate_hz, axis=0)
        acceleration[begin:end] = np.gradient(velocity[begin:end], 1.0 / rate_hz, axis=0)
        # Within half a period of the cutoff of a run's ends the padding, not the arm, shapes the derivatives.
        edge = min(int(0.5 * rate_hz / cutoff_hz), (end - begin) // 4)
        for series in (velocity, acceleration):
            series[begin : begin + edge] = np.nan
            series[end - edge : end] = np.nan
    return velocity, acceleration


def kinematics_from_angles(
    t_ns: npt.ArrayLike,
    q_rad: npt.ArrayLike,
    lengths_m: npt.ArrayLike,
    config: KinematicsConfig | None = None,
    angle_filter: bool = False,
) -> MarkerKinematics:
    """Put already-estimated joint angles (e.g. a live `arm/joint_states` stream) on a uniform grid.

    Gaps longer than ``max_gap_s`` are not bridged; direction velocities are smoothed with zero phase.

    Parameters
    ----------
    t_ns : (M,) strictly increasing stamps (ns).
    q_rad : (M, n) joint angles (rad).
    lengths_m : (n,) segment lengths (m).
    config : gap and filter settings.
    angle_filter : also low-pass the angles (False when the source already filtered them).
    """
    config = config or KinematicsConfig()
    stamps = np.asarray(t_ns, dtype=np.int64)
    angles = np.asarray(q_rad, dtype=np.float64)
    if stamps.size < 16:
        raise DataError(f"{stamps.size} joint-angle samples: at least 16 are needed")
    step_ns = round(float(np.median(np.diff(stamps))))
    grid_ns = stamps[0] + step_ns * np.arange((stamps[-1] - stamps[0]) // step_ns + 1, dtype=np.int64)
    gridded, _ = _grid_values(grid_ns, stamps, angles, int(config.max_gap_s * 1e9) + step_ns // 2)
    config, widened = config_for_motion(config, gridded, 1e9 / step_ns)
    q_grid, velocity, noise, notes = _filtered_runs(gridded, 1e9 / step_ns, config, angle_filter)
    notes = widened + notes
    lengths = np.asarray(lengths_m, dtype=np.float64)
    invalid = int((~np.isfinite(q_grid).all(axis=1)).sum())
    qd, qdd = _motion_runs(gridded, q_grid, 1e9 / step_ns, config.dynamics_cutoff_hz)
    return MarkerKinematics(
        grid_ns, q_grid, velocity, lengths, np.zeros_like(lengths), {}, invalid, noise, notes, {}, qd, qdd
    )


def kinematics_from_markers(
    markers: dict[str, MarkerSeries], n_segments: int, config: KinematicsConfig | None = None
) -> MarkerKinematics:
    """Joint angles, direction velocities and segment lengths from marker trajectories.

    Parameters
    ----------
    markers : marker name -> series in ``world`` (m); names per CONTRACT.md (``wrist`` only for 3 segments).
    n_segments : 2 or 3.
    config : filter and gap settings.

    Returns
    -------
    MarkerKinematics on a uniform grid at the marker rate.

    Raises
    ------
    DataError
        A marker is missing or too sparse to give any angle.
    """
    config = config or KinematicsConfig()
    if n_segments not in (2, 3):
        raise InputError(f"n_segments must be 2 or 3, got {n_segments!r}")
    names = markers_for(n_segments)
    missing = [name for name in names if name not in markers]
    if missing:
        raise DataError(f"missing marker(s) {missing}: a {n_segments}-segment chain needs {list(names)}")
    warnings: list[str] = []
    cleaned = {}
    for name in names:
        t_ns, position, notes = _clean_marker(name, markers[name])
        warnings += notes
        if t_ns.size < 10:
            raise DataError(f"marker {name!r} has {t_ns.size} usable frames; at least 10 are needed")
        cleaned[name] = (t_ns, position)
    rejected, notes = _remove_chain_outliers(cleaned, names, config)
    warnings += notes
    lengths_m, lengths_std_m = _segment_lengths(cleaned, names)

    step_ns = round(float(np.median(np.concatenate([np.diff(t) for t, _ in cleaned.values()]))))
    start_ns = min(int(t[0]) for t, _ in cleaned.values())
    stop_ns = max(int(t[-1]) for t, _ in cleaned.values())
    grid_ns = start_ns + step_ns * np.arange((stop_ns - start_ns) // step_ns + 1, dtype=np.int64)
    max_gap_ns = int(config.max_gap_s * 1e9) + step_ns // 2

    points = np.empty((grid_ns.size, len(names), 2))
    bridged = {}
    for k, name in enumerate(names):
        t_ns, position = cleaned[name]
        gridded, bridged[name] = _grid_values(grid_ns, t_ns, sagittal_from_world(position), max_gap_ns)
        points[:, k] = gridded
    raw_q = joint_angles_from_positions(points)
    config, widened = config_for_motion(config, raw_q, 1e9 / step_ns)
    q_rad, velocity, noise, notes = _filtered_runs(raw_q, 1e9 / step_ns, config, trim_edges=True)
    warnings += widened + notes
    n_invalid = int((~np.isfinite(q_rad).all(axis=1)).sum())
    if n_invalid:
        warnings.append(
            f"{n_invalid} of {grid_ns.size} marker frames give no angle (gaps over {config.max_gap_s} s or short runs)"
        )
    qd, qdd = _motion_runs(raw_q, q_rad, 1e9 / step_ns, config.dynamics_cutoff_hz)
    return MarkerKinematics(
        grid_ns, q_rad, velocity, lengths_m, lengths_std_m, bridged, n_invalid, noise, warnings, rejected, qd, qdd
    )


def resample_kinematics(kinematics: MarkerKinematics, t_ns: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Interpolate angles and direction velocities onto other stamps (the wrench's).

    Parameters
    ----------
    kinematics : angles on the marker grid.
    t_ns : (N,) int64 target stamps.

    Returns
    -------
    q_rad : (N, n) angles (rad), NaN where invalid.
    velocity_rad_s : (N, n) direction velocities (rad/s), NaN where invalid.
    valid : (N,) bool, True where both neighbouring grid frames are valid.
    """
    target = np.asarray(t_ns, dtype=np.int64)
    grid = kinematics.t_ns
    step = float(grid[1] - grid[0]) if grid.size > 1 else 1.0
    position = (target - grid[0]).astype(np.float64) / step
    lower = np.floor(position).astype(np.int64)
    inside = (lower >= 0) & (lower < grid.size - 1)
    lower_c = np.clip(lower, 0, max(grid.size - 2, 0))
    frac = (position - lower_c)[:, None]
    exact_last = position == grid.size - 1
    lower_c = np.where(exact_last, grid.size - 2, lower_c)
    frac = np.where(exact_last[:, None], 1.0, frac)
    inside |= exact_last

    def blend(values: np.ndarray) -> np.ndarray:
        return (1.0 - frac) * values[lower_c] + frac * values[lower_c + 1]

    q_rad = blend(kinematics.q_rad)
    velocity = blend(kinematics.direction_velocity_rad_s)
    valid = inside & np.isfinite(q_rad).all(axis=1) & np.isfinite(velocity).all(axis=1)
    q_rad[~valid] = np.nan
    velocity[~valid] = np.nan
    return q_rad, velocity, valid


def resample_motion(kinematics: MarkerKinematics, t_ns: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Velocities and accelerations (N, n) of :class:`MarkerKinematics` at other stamps (zeros if absent; NaN
    near gaps and the ends of runs)."""
    target = np.asarray(t_ns, dtype=np.int64)
    n = kinematics.q_rad.shape[1]
    if kinematics.velocity_rad_s is None or kinematics.acceleration_rad_s2 is None:
        return np.zeros((target.size, n)), np.zeros((target.size, n))
    grid = (kinematics.t_ns - kinematics.t_ns[0]).astype(np.float64)
    where = (target - kinematics.t_ns[0]).astype(np.float64)
    out = []
    for values in (kinematics.velocity_rad_s, kinematics.acceleration_rad_s2):
        # NaN (a gap or a run's edge) spreads to the samples beside it: those have no usable derivative.
        column = [np.interp(where, grid, values[:, j]) for j in range(n)]
        out.append(np.column_stack(column))
    return out[0], out[1]


def resample_with_motion(
    kinematics: MarkerKinematics, t_ns: npt.ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`resample_kinematics` with the joint velocities and accelerations of the inertial torques.

    Returns
    -------
    q_rad, velocity_rad_s, qd_rad_s, qdd_rad_s2 : (N, n) each.
    valid : (N,) bool, also False where the derivatives are unknown: near gaps and the ends of runs (the
        zero-phase filter's edge, hence the newest half second of a live window). Taken as a still arm there,
        the inertial torque would bias the fit; offline and live drop those samples alike.
    """
    q_rad, velocity, valid = resample_kinematics(kinematics, t_ns)
    qd, qdd = resample_motion(kinematics, t_ns)
    valid &= np.isfinite(qd).all(axis=1) & np.isfinite(qdd).all(axis=1)
    return q_rad, velocity, qd, qdd, valid
