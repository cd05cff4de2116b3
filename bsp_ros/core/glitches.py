"""Glitched copies of a session's streams: swapped or jumping markers and wrench spikes, for robustness tests.

Every function takes a :class:`bsp_ros.core.streams.Session` and returns a new one; the input is never changed.
Frame and sample indices count the rows of the series as stored (time order for simulated sessions).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import numpy.typing as npt

from bsp_ros.core.streams import MarkerSeries, Session, WrenchSeries
from bsp_ros.errors import InputError


def _marker(session: Session, name: str) -> MarkerSeries:
    if name not in session.markers:
        raise InputError(f"no marker {name!r} in the session (markers: {sorted(session.markers)})")
    return session.markers[name]


def _with_marker(session: Session, name: str, position_m: np.ndarray) -> Session:
    markers = dict(session.markers)
    markers[name] = MarkerSeries(session.markers[name].t_ns.copy(), position_m)
    return dataclasses.replace(session, markers=markers)


def _check_index(what: str, index: int, size: int) -> int:
    if not -size <= int(index) < size:
        raise InputError(f"{what} index {index} is outside the {size} rows")
    return int(index) % size


def displace_marker(session: Session, name: str, frame: int, offset_m: npt.ArrayLike) -> Session:
    """One frame of one marker moved by ``offset_m`` (a single-frame jump, e.g. a mislabelled reflection).

    Parameters
    ----------
    session : the streams.
    name : marker name (``shoulder``, ``elbow``, ``wrist``, ``hand``).
    frame : row of that marker's series.
    offset_m : (3,) displacement in ``world`` (m).

    Returns
    -------
    A copy of the session with that one position moved.
    """
    series = _marker(session, name)
    row = _check_index(f"marker {name} frame", frame, series.t_ns.size)
    offset = np.asarray(offset_m, dtype=np.float64)
    if offset.shape != (3,):
        raise InputError(f"offset_m must be 3 numbers, got shape {offset.shape}")
    position = np.array(series.position_m, dtype=np.float64, copy=True)
    position[row] += offset
    return _with_marker(session, name, position)


def swap_markers(session: Session, first: str, second: str, frame: int) -> Session:
    """Two markers' labels exchanged in one frame (the classic mocap swap).

    Parameters
    ----------
    session : the streams.
    first, second : marker names.
    frame : row of ``first``'s series; ``second`` must have a frame with the same stamp.

    Returns
    -------
    A copy of the session in which, at that stamp, each marker carries the other's position.
    """
    a, b = _marker(session, first), _marker(session, second)
    row_a = _check_index(f"marker {first} frame", frame, a.t_ns.size)
    matches = np.flatnonzero(b.t_ns == a.t_ns[row_a])
    if matches.size == 0:
        raise InputError(f"marker {second} has no frame at the stamp of {first} frame {frame}")
    row_b = int(matches[0])
    pos_a = np.array(a.position_m, dtype=np.float64, copy=True)
    pos_b = np.array(b.position_m, dtype=np.float64, copy=True)
    pos_a[row_a], pos_b[row_b] = b.position_m[row_b], a.position_m[row_a]
    return _with_marker(_with_marker(session, first, pos_a), second, pos_b)


def _with_wrench(session: Session, force_n: np.ndarray, torque_nm: np.ndarray) -> Session:
    w = session.wrench
    return dataclasses.replace(session, wrench=WrenchSeries(w.t_ns.copy(), force_n, torque_nm, w.frame_id))


def wrench_spikes(
    session: Session, count: int, force_n: float = 1000.0, seed: int = 0, axis: int | None = None
) -> Session:
    """``count`` wrench samples replaced by a force of magnitude ``force_n`` (contact spikes, saturation).

    Parameters
    ----------
    session : the streams.
    count : number of distinct samples hit, drawn uniformly without replacement.
    force_n : magnitude of the spike force (N); its direction is a random unit vector, or the sensor
        axis ``axis`` (0, 1, 2) with a random sign.
    seed : seed of the draw.
    axis : see ``force_n``.

    Returns
    -------
    A copy of the session; the torque of the spiked samples is left as it was.
    """
    w = session.wrench
    n = int(np.asarray(w.t_ns).size)
    if not 0 <= count <= n:
        raise InputError(f"count must be within 0..{n}, got {count}")
    if not np.isfinite(force_n):
        raise InputError(f"force_n must be finite, got {force_n} (use set_wrench_sample for non-finite values)")
    rng = np.random.default_rng(seed)
    rows = rng.choice(n, size=count, replace=False)
    if axis is None:
        direction = rng.normal(size=(count, 3))
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    else:
        direction = np.zeros((count, 3))
        direction[:, axis] = rng.choice((-1.0, 1.0), size=count)
    force = np.array(w.force_n, dtype=np.float64, copy=True)
    force[rows] = force_n * direction
    return _with_wrench(session, force, np.array(w.torque_nm, dtype=np.float64, copy=True))


def set_wrench_sample(session: Session, index: int, value: float, component: int = 0) -> Session:
    """One component of one wrench sample set to ``value`` (e.g. 1e30, NaN): ``component`` 0-2 is force
    x, y, z (N), 3-5 torque x, y, z (Nm).

    Returns
    -------
    A copy of the session.
    """
    w = session.wrench
    row = _check_index("wrench sample", index, int(np.asarray(w.t_ns).size))
    if not 0 <= component < 6:
        raise InputError(f"component must be 0..5, got {component}")
    force = np.array(w.force_n, dtype=np.float64, copy=True)
    torque = np.array(w.torque_nm, dtype=np.float64, copy=True)
    (force if component < 3 else torque)[row, component % 3] = value
    return _with_wrench(session, force, torque)


__all__ = ["displace_marker", "set_wrench_sample", "swap_markers", "wrench_spikes"]
