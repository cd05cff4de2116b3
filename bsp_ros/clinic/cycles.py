"""Within-session repeatability: the session cut into cycles of motion, each identified through the pipeline.

It tells how repeatable one session's estimate is; it leaves out everything that differs between days
(markers re-placed, arm re-strapped, sensor re-zeroed), so it never judges a change between sessions:
that is what retest pairs are for (:mod:`bsp_ros.clinic.mdc`).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.clinic.mdc import successive_difference_sem
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.core.streams import MarkerSeries, Session, WrenchSeries, markers_for
from bsp_ros.errors import BspError

CYCLE_METHOD = (
    "Within-session spread: the session is cut into full cycles of motion (between alternate direction "
    "reversals of the joint that reverses least often), each cycle is identified on its own with the session's "
    "settings, and SEM = sqrt(sum (x[k+1] - x[k])^2 / (2 (K - 1))) over the K valid cycles. It describes one "
    "session only and is not used to judge changes between sessions."
)
MIN_CYCLES = 3
"""Fewer valid cycles give no SEM (two cycles give one difference: too few to trust)."""
SMOOTH_S = 2.0
"""Angles are smoothed over this window before differentiating: motions last 15-25 s per cycle."""


def direction_reversals(velocity_rad_s: npt.ArrayLike, hysteresis: float = 0.2) -> np.ndarray:
    """Sample indices where a joint's direction of motion reverses.

    Parameters
    ----------
    velocity_rad_s : (N,) direction-of-motion velocity of one joint (rad/s), already low-pass filtered.
    hysteresis : a new direction counts once the speed exceeds this fraction of the 95th-percentile speed,
        so noise around a turning point is not taken for several reversals.

    Returns
    -------
    (R,) int indices: the middle of the zero crossings before each confirmed change of direction.
    """
    v = np.asarray(velocity_rad_s, dtype=np.float64)
    finite = np.isfinite(v)
    if finite.sum() < 3:
        return np.zeros(0, dtype=np.int64)
    threshold = hysteresis * float(np.percentile(np.abs(v[finite]), 95))
    if threshold <= 0:
        return np.zeros(0, dtype=np.int64)
    state = 0
    first_zero = last_zero = -1  # sign changes since the last confirmed direction
    reversals = []
    for i, value in enumerate(v):
        if not math.isfinite(value):
            continue
        if i > 0 and math.isfinite(v[i - 1]) and (v[i - 1] > 0) != (value > 0):
            first_zero = i if first_zero < 0 else first_zero
            last_zero = i
        direction = 1 if value > threshold else -1 if value < -threshold else 0
        if direction and direction != state:
            if state and first_zero >= 0:
                reversals.append((first_zero + last_zero) // 2)  # noise crosses zero several times: the middle
            state = direction
        if direction:
            first_zero = last_zero = -1
    return np.asarray(reversals, dtype=np.int64)


def cycle_bounds(velocity_rad_s: npt.ArrayLike) -> list[tuple[int, int]]:
    """Full cycles of motion as ``(start, stop)`` row ranges.

    The reference joint is the one that reverses least often (at least three times), so every joint
    moves both ways within each of its cycles; a cycle runs from one of its reversals to the next but one.

    Parameters
    ----------
    velocity_rad_s : (N, n) direction-of-motion velocities (rad/s).
    """
    v = np.atleast_2d(np.asarray(velocity_rad_s, dtype=np.float64))
    per_joint = [direction_reversals(v[:, j]) for j in range(v.shape[1])]
    usable = [r for r in per_joint if r.size >= 3]
    if not usable:
        return []
    reversals = min(usable, key=lambda r: r.size)
    edges = reversals[::2]
    return [(int(a), int(b)) for a, b in itertools.pairwise(edges.tolist())]


def joint_velocities(session: Session) -> tuple[np.ndarray, np.ndarray]:
    """Smoothed planar joint velocities from the markers, for finding cycles (not for identification).

    Returns
    -------
    t_ns : (M,) int64 stamps of the first marker's frames.
    velocity_rad_s : (M, n) relative joint angle rates.
    """
    names = markers_for(session.n_segments)
    base = session.markers[names[0]]
    t_ns = base.t_ns
    if t_ns.size < 10:
        return t_ns, np.zeros((t_ns.size, len(names) - 1))
    t_s = (t_ns - t_ns[0]) / 1e9
    yz = []
    for name in names:
        series = session.markers[name]
        ts = (series.t_ns - t_ns[0]) / 1e9
        yz.append(np.column_stack([np.interp(t_s, ts, series.position_m[:, k]) for k in (1, 2)]))
    absolute = np.column_stack(
        [np.unwrap(np.arctan2(b[:, 1] - a[:, 1], b[:, 0] - a[:, 0])) for a, b in itertools.pairwise(yz)]
    )
    relative = np.column_stack([absolute[:, 0], np.diff(absolute, axis=1)]) if absolute.shape[1] > 1 else absolute
    step_s = float(np.median(np.diff(t_s))) or 0.02
    width = max(1, round(SMOOTH_S / step_s))
    kernel = np.ones(width) / width
    smooth = np.column_stack([np.convolve(relative[:, j], kernel, mode="same") for j in range(relative.shape[1])])
    velocity = np.gradient(smooth, t_s, axis=0)
    velocity[: width // 2 + 1] = np.nan  # the moving average is biased at the ends
    velocity[-(width // 2 + 1) :] = np.nan
    return t_ns, velocity


def window(session: Session, start_ns: int, stop_ns: int) -> Session:
    """The part of ``session`` stamped within ``[start_ns, stop_ns)``."""

    def cut(t_ns: np.ndarray) -> np.ndarray:
        return (t_ns >= start_ns) & (t_ns < stop_ns)

    def cut_series(series: MarkerSeries) -> MarkerSeries:
        keep = cut(series.t_ns)
        return MarkerSeries(series.t_ns[keep], series.position_m[keep])

    w = session.wrench
    keep = cut(w.t_ns)
    wrench = WrenchSeries(w.t_ns[keep], w.force_n[keep], w.torque_nm[keep], w.frame_id)
    markers = {name: cut_series(m) for name, m in session.markers.items()}
    pose = None if session.handle_pose is None else cut_series(session.handle_pose)
    return replace(session, wrench=wrench, markers=markers, handle_pose=pose)


@dataclass(frozen=True)
class CycleRepeatability:
    """Per-parameter SEM of one session from its cycles (``group.part.quantity`` keys)."""

    n_cycles: int
    n_valid_cycles: int
    sem: dict[str, float]
    cycle_values: dict[str, list[float]]
    message: str = ""

    def to_json(self) -> dict[str, Any]:
        """The ``repeatability`` block of an estimate JSON (and of a stored session)."""
        return {
            "method": CYCLE_METHOD,
            "n_cycles": self.n_cycles,
            "n_valid_cycles": self.n_valid_cycles,
            "message": self.message,
            "parameters": {key: {"sem": sem, "n": len(self.cycle_values[key])} for key, sem in self.sem.items()},
        }


def cycle_repeatability(
    session: Session, options: IdentifyOptions | None = None, min_cycles: int = MIN_CYCLES
) -> CycleRepeatability:
    """SEM of every data-determined parameter from the session's cycle-to-cycle spread.

    Each cycle is identified with :func:`bsp_ros.core.pipeline.identify_session` and ``options`` (tare,
    passive model, subject), like the whole session.
    """
    t_ns, velocity = joint_velocities(session)
    bounds = cycle_bounds(velocity)
    documents = []
    for start, stop in bounds:
        try:
            document = identify_session(window(session, int(t_ns[start]), int(t_ns[stop])), options)
        except BspError:
            continue
        if document["quality"]["valid"]:
            documents.append(document)
    if len(documents) < min_cycles:
        message = f"only {len(documents)} valid cycle(s) of {len(bounds)} found (need {min_cycles})"
        return CycleRepeatability(len(bounds), len(documents), {}, {}, message)
    values: dict[str, list[float]] = {}
    for document in documents:
        for group in ("segments", "joints"):
            for part, quantities in document[group].items():
                for name, q in quantities.items():
                    if isinstance(q, dict) and q.get("source") == "data" and isinstance(q.get("value"), int | float):
                        values.setdefault(f"{group}.{part}.{name}", []).append(float(q["value"]))
    values = {k: v for k, v in values.items() if len(v) == len(documents)}
    sem = {k: successive_difference_sem(v) for k, v in values.items()}
    return CycleRepeatability(len(bounds), len(documents), sem, values)
