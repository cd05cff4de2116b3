"""Zero-phase filtered angles, velocities and accelerations of the chain, from markers or from angles."""

from __future__ import annotations

import functools

import numpy as np
import numpy.typing as npt

from bsp_ros.core.filters import butter_lowpass_sos, zero_phase_lowpass
from bsp_ros.core.identification.robust import robust_sd
from bsp_ros.core.joint_angles.config import KinematicsConfig, MarkerKinematics
from bsp_ros.core.joint_angles.geometry import joint_angles_from_positions, sagittal_from_world
from bsp_ros.core.joint_angles.markers import clean_marker, grid_values, remove_chain_outliers, segment_lengths
from bsp_ros.core.motion_band import config_for_motion
from bsp_ros.core.streams import MarkerSeries, markers_for
from bsp_ros.errors import DataError, InputError


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
    return np.asarray(angle_sd * direction_noise_gain(config.direction_cutoff_hz, rate_hz))


@functools.lru_cache(maxsize=64)
def direction_noise_gain(direction_cutoff_hz: float, rate_hz: float) -> float:
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
    adapt_to_motion: bool = True,
    grid: tuple[int, int] | None = None,
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
    adapt_to_motion : raise the direction and dynamics cutoffs to the motion's band (:func:`config_for_motion`);
        False uses ``config`` as given (e.g. the returned ``config`` of an earlier call on the same motion).
    grid : ``(origin_ns, step_ns)``: the grid's points are ``origin_ns + k step_ns`` within the stamps (so that
        an earlier call's grid continues, e.g. a live window's newest seconds); None starts it at the first stamp,
        stepped by the stamps' median interval.
    """
    config = config or KinematicsConfig()
    stamps = np.asarray(t_ns, dtype=np.int64)
    angles = np.asarray(q_rad, dtype=np.float64)
    if stamps.size < 16:
        raise DataError(f"{stamps.size} joint-angle samples: at least 16 are needed")
    if grid is None:
        origin_ns, step_ns = int(stamps[0]), round(float(np.median(np.diff(stamps))))
    else:
        origin_ns, step_ns = int(grid[0]), int(grid[1])
    first = -(-(int(stamps[0]) - origin_ns) // step_ns)  # the first grid point at or after the first stamp
    grid_ns = origin_ns + step_ns * np.arange(first, (int(stamps[-1]) - origin_ns) // step_ns + 1, dtype=np.int64)
    if grid_ns.size < 16:
        raise DataError(f"{grid_ns.size} joint-angle grid points: at least 16 are needed")
    gridded, _ = grid_values(grid_ns, stamps, angles, int(config.max_gap_s * 1e9) + step_ns // 2)
    config, widened = config_for_motion(config, gridded, 1e9 / step_ns) if adapt_to_motion else (config, [])
    q_grid, velocity, noise, notes = _filtered_runs(gridded, 1e9 / step_ns, config, angle_filter)
    notes = widened + notes
    lengths = np.asarray(lengths_m, dtype=np.float64)
    invalid = int((~np.isfinite(q_grid).all(axis=1)).sum())
    qd, qdd = _motion_runs(gridded, q_grid, 1e9 / step_ns, config.dynamics_cutoff_hz)
    return MarkerKinematics(
        t_ns=grid_ns,
        q_rad=q_grid,
        direction_velocity_rad_s=velocity,
        lengths_m=lengths,
        lengths_std_m=np.zeros_like(lengths),
        n_frames_bridged={},
        n_frames_invalid=invalid,
        direction_velocity_noise_rad_s=noise,
        warnings=notes,
        n_frames_rejected={},
        velocity_rad_s=qd,
        acceleration_rad_s2=qdd,
        config=config,
    )


def kinematics_from_markers(
    markers: dict[str, MarkerSeries], n_segments: int, config: KinematicsConfig | None = None
) -> MarkerKinematics:
    """Joint angles, direction velocities and segment lengths from marker trajectories.

    Parameters
    ----------
    markers : marker name -> series in ``world`` (m); names per docs/contract.md (``wrist`` only for 3 segments).
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
        t_ns, position, notes = clean_marker(name, markers[name])
        warnings += notes
        if t_ns.size < 10:
            raise DataError(f"marker {name!r} has {t_ns.size} usable frames; at least 10 are needed")
        cleaned[name] = (t_ns, position)
    rejected, notes = remove_chain_outliers(cleaned, names, config)
    warnings += notes
    lengths_m, lengths_std_m = segment_lengths(cleaned, names)

    step_ns = round(float(np.median(np.concatenate([np.diff(t) for t, _ in cleaned.values()]))))
    start_ns = min(int(t[0]) for t, _ in cleaned.values())
    stop_ns = max(int(t[-1]) for t, _ in cleaned.values())
    grid_ns = start_ns + step_ns * np.arange((stop_ns - start_ns) // step_ns + 1, dtype=np.int64)
    max_gap_ns = int(config.max_gap_s * 1e9) + step_ns // 2

    points = np.empty((grid_ns.size, len(names), 2))
    bridged = {}
    for k, name in enumerate(names):
        t_ns, position = cleaned[name]
        gridded, bridged[name] = grid_values(grid_ns, t_ns, sagittal_from_world(position), max_gap_ns)
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
        t_ns=grid_ns,
        q_rad=q_rad,
        direction_velocity_rad_s=velocity,
        lengths_m=lengths_m,
        lengths_std_m=lengths_std_m,
        n_frames_bridged=bridged,
        n_frames_invalid=n_invalid,
        direction_velocity_noise_rad_s=noise,
        warnings=warnings,
        n_frames_rejected=rejected,
        velocity_rad_s=qd,
        acceleration_rad_s2=qdd,
    )
