"""Minimal detectable change: the standard error of measurement from repeated cycles (and baseline sessions)."""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.streams import segments_for

Z95 = 1.96
"""The two-sided 95 % normal quantile of MDC95 = 1.96 x sqrt(2) x SEM."""

CYCLE_METHOD = (
    "SEM from the within-session cycle-to-cycle spread: the session is cut into full cycles of motion "
    "(between alternate direction reversals of the joint that reverses least often), each cycle is identified "
    "on its own with the session's method, and SEM = sqrt(sum (x[k+1] - x[k])^2 / (2 (K - 1))) over the K "
    "valid cycles (successive differences: SD of the differences / sqrt(2), insensitive to slow drift). "
    "It is the SEM of a one-cycle measurement, larger than that of the whole-session estimate, so the "
    "MDC95 = 1.96 x sqrt(2) x SEM built on it is conservative."
)
BASELINE_METHOD = (
    "SEM from the subject's baseline sessions (test-retest): the same successive-difference formula over "
    "the baseline sessions' estimates; where both are known the larger SEM is used."
)
MIN_CYCLES = 3
"""Fewer valid cycles give no SEM (two cycles give one difference: too few to trust)."""


def mdc95_from_sem(sem: float) -> float:
    """MDC95 = 1.96 x sqrt(2) x SEM: the smallest change between two measurements beyond their 95 % noise."""
    return Z95 * math.sqrt(2.0) * sem


def pair_mdc95(sem_a: float, sem_b: float) -> float:
    """MDC95 between measurements of SEM ``sem_a`` and ``sem_b``: 1.96 sqrt(a^2 + b^2) (= the above if equal)."""
    return Z95 * math.hypot(sem_a, sem_b)


def successive_difference_sem(values: npt.ArrayLike) -> float:
    """SEM of repeated measurements ``values`` (K,) from successive differences; NaN if fewer than 2 finite.

    ``sqrt(sum (x[k+1] - x[k])^2 / (2 (K - 1)))``: for independent repeats of one true value it estimates their
    SD (the difference of two has variance 2 SEM^2), and a slow drift inflates it far less than the plain SD.
    """
    x = np.asarray(values, dtype=np.float64)
    x = x[np.isfinite(x)]
    if x.size < 2:
        return math.nan
    return float(np.sqrt(np.sum(np.diff(x) ** 2) / (2.0 * (x.size - 1))))


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

    Returns
    -------
    list of (start, stop) consecutive, non-overlapping ranges; empty if no joint reverses three times.
    """
    v = np.atleast_2d(np.asarray(velocity_rad_s, dtype=np.float64))
    per_joint = [direction_reversals(v[:, j]) for j in range(v.shape[1])]
    usable = [r for r in per_joint if r.size >= 3]
    if not usable:
        return []
    reversals = min(usable, key=lambda r: r.size)
    edges = reversals[::2]
    return [(int(a), int(b)) for a, b in itertools.pairwise(edges.tolist())]


def parameter_key(name: tuple[str, str], n_segments: int) -> str:
    """``("static_moment_kgm", "forearm")`` -> ``segments.forearm.static_moment_kgm`` (estimate JSON path)."""
    quantity, owner = name
    group = "segments" if owner in segments_for(n_segments) else "joints"
    return f"{group}.{owner}.{quantity}"


@dataclass(frozen=True)
class Repeatability:
    """Per-parameter SEM and MDC95 of one session.

    Attributes
    ----------
    method : how the SEM was obtained (plain words and the formula).
    n_cycles : cycles found; n_valid_cycles of them identified as valid.
    sem : estimate-JSON path (``joints.elbow.coulomb_nm``) -> SEM (units of the parameter).
    cycle_values : the same keys -> (K,) per-cycle estimates of the valid cycles.
    message : why there is no SEM, if there is none.
    """

    method: str
    n_cycles: int
    n_valid_cycles: int
    sem: dict[str, float]
    cycle_values: dict[str, list[float]]
    message: str = ""

    @property
    def mdc95(self) -> dict[str, float]:
        """MDC95 = 1.96 x sqrt(2) x SEM per parameter."""
        return {key: mdc95_from_sem(sem) for key, sem in self.sem.items()}

    def to_json(self) -> dict[str, Any]:
        """The ``repeatability`` block of an estimate JSON (and of a stored session)."""
        return {
            "method": self.method,
            "n_cycles": self.n_cycles,
            "n_valid_cycles": self.n_valid_cycles,
            "message": self.message,
            "parameters": {
                key: {"sem": sem, "mdc95": mdc95_from_sem(sem), "n": len(self.cycle_values[key])}
                for key, sem in self.sem.items()
            },
        }


def repeatability(
    data: IdentificationData, config: JointConfig | None = None, min_cycles: int = MIN_CYCLES
) -> Repeatability:
    """SEM and MDC95 of every identified parameter from the session's cycle-to-cycle spread.

    Parameters
    ----------
    data : the session's identification samples.
    config : the identification settings (the elastic check is skipped per cycle: it is a second fit).
    min_cycles : fewer valid cycles give no SEM (the result says why).

    Returns
    -------
    Repeatability
        Empty ``sem`` with a ``message`` when the session holds too few valid cycles.
    """
    base = config or JointConfig()
    per_cycle = JointConfig(
        passive=base.passive,
        deadband_fraction=base.deadband_fraction,
        deadband_noise_sd=base.deadband_noise_sd,
        min_samples=base.min_samples,
        min_range_deg=base.min_range_deg,
        min_direction_share=base.min_direction_share,
        max_condition=base.max_condition,
        check_elastic=False,
    )
    bounds = cycle_bounds(data.velocity_rad_s)
    results: list[IdentificationResult] = []
    for start, stop in bounds:
        result = identify_joint(data.window(start, stop), per_cycle)
        if result.valid:
            results.append(result)
    if len(results) < min_cycles:
        return Repeatability(
            CYCLE_METHOD,
            len(bounds),
            len(results),
            {},
            {},
            f"only {len(results)} valid cycle(s) of {len(bounds)} found (need {min_cycles}): no SEM for this session",
        )
    n = data.n_joints
    values: dict[str, list[float]] = {}
    for i, name in enumerate(results[0].names):
        values[parameter_key(name, n)] = [float(r.values[i]) for r in results]
    sem = {key: successive_difference_sem(v) for key, v in values.items()}
    return Repeatability(CYCLE_METHOD, len(bounds), len(results), sem, values)


def baseline_sem(values: Sequence[float | None]) -> float:
    """SEM from baseline sessions' estimates of one parameter (successive differences); NaN if < 2 values."""
    return successive_difference_sem([math.nan if v is None else v for v in values])


def sem_of(block: Mapping[str, Any] | None, key: str) -> float | None:
    """The SEM of parameter ``key`` in a stored ``repeatability`` block, or None."""
    if not block:
        return None
    entry = block.get("parameters", {}).get(key)
    if not isinstance(entry, Mapping):
        return None
    sem = entry.get("sem")
    return float(sem) if isinstance(sem, int | float) and math.isfinite(sem) and sem >= 0 else None
