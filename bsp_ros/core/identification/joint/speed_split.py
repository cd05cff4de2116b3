"""Two speeds: the speed-dependent (neural) resistance of a joint apart from its passive, speed-independent part.

A stretch reflex resists a fast stretch and not a slow one (Lance 1980); a relaxed joint's friction and elasticity
barely change between a robot's slow speeds. Where a session moves a joint over the same angles at two clearly
separated speeds (a plan's ``--speeds SLOW FAST``, or any session that does so: the groups are found in the data,
never taken from a flag), the resistance at the fast speed minus that at the slow speed, beyond what the model's
passive terms (a viscous term, if any) explain, is measured per direction of motion: the model is fitted on the
slow part (the joint's fast strokes left out of its own equation), and the fast strokes' mean torque beyond it,
with the motion's sign, is the extra resistance in Nm, its std the mean's HAC variance plus the slow fit's. A
model fitted on both speeds would take up part of a reflex that varies along each stroke in its static moments,
and give some of it to the other direction. This is the split of NeuroFlexor (Lindberg et al. 2011: a slow and a
fast stretch separate the neural part from the elastic and viscous ones) on a slow robot's sweeps, with the
passive part taken out first (McPherson et al. 2019).

Where the fast part shows such resistance (more than 3 std from 0 in a direction), the joint's static moments come
from the slow part: the fast strokes' rows leave that joint's torque equation (a joint's own muscle torque acts
between its two segments and enters no other joint's equation) and the model is refitted. Where the two speeds
agree, the estimate stays as it is. Either way the note ``speed_dependent_resistance`` carries the measurement; a
part in one direction only is also named as possible spasticity.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.covariance import hac_covariance
from bsp_ros.core.identification.joint.stage import Outcome, Stage
from bsp_ros.core.identification.joint.transition import transition_widths
from bsp_ros.core.identification.stacked import Fit, Problem, build_problem, fit_problem
from bsp_ros.core.streams import joints_for

__all__ = [
    "DIRECTIONS",
    "EXCEEDS_SD",
    "MIN_SPASTIC_NM",
    "DirectionPart",
    "SpeedGroups",
    "SpeedSplit",
    "measure_speed_split",
    "speed_dependence_block",
    "speed_groups",
    "split_speeds",
]

# Two speeds are clearly separated when the slowest fast stroke is at least this many times as fast as the
# fastest slow one (sorted stroke speeds: the largest ratio between neighbours).
SPLIT_RATIO = 2.0
# A stroke (one run of one direction of motion) shorter than this says nothing of its speed group, s.
MIN_STROKE_S = 1.0
# Strokes each speed group needs in each direction (one sweep of the range each way, as a clinical stretch test).
MIN_STROKES = 1
# Each speed group holds at least this share of the long strokes' time.
MIN_GROUP_SHARE = 0.1
# The two groups' angle ranges overlap over at least this share of the narrower one (the same angles).
MIN_OVERLAP = 0.5
# Each direction's fast rows: at least this many in the fit (the extra column's std holds few otherwise).
MIN_FAST_ROWS = 200
# Where the slow strokes hold less than this share of a joint's rows, its static moments stay the whole session's.
MIN_SLOW_SHARE = 0.25
# A speed-dependent part this many std from 0 is measured; the static moments then come from the slow part.
EXCEEDS_SD = 3.0
# Below this a one-direction part is not named as possible spasticity (it moves no estimate a clinic reads), Nm.
MIN_SPASTIC_NM = 0.02
# The two directions of motion, in the sign of the joint velocity (docs/contract.md conventions).
DIRECTIONS = ("positive", "negative")


@dataclass(frozen=True, kw_only=True)
class SpeedGroups:
    """One joint's two speed groups.

    Attributes
    ----------
    fast : (N,) bool, the samples in the fast strokes (every stroke faster than the split, short ones too).
    slow_rad_s, fast_rad_s : the median stroke speed of each group (each stroke's 90th percentile speed), rad/s.
    """

    fast: np.ndarray
    slow_rad_s: float
    fast_rad_s: float


def _strokes(velocity_rad_s: np.ndarray) -> list[tuple[int, int]]:
    """``[start, end)`` indices of each run of one nonzero sign of ``velocity_rad_s`` (N,)."""
    sign = np.sign(velocity_rad_s).astype(np.int8)
    edges = np.flatnonzero(np.diff(sign)) + 1
    bounds = np.concatenate(([0], edges, [sign.size]))
    return [(int(a), int(b)) for a, b in itertools.pairwise(bounds) if sign[a] != 0]


def _overlap(first: tuple[float, float], second: tuple[float, float]) -> float:
    """The share of the narrower of two angle ranges that the other covers."""
    shared = min(first[1], second[1]) - max(first[0], second[0])
    narrower = min(first[1] - first[0], second[1] - second[0])
    return max(shared, 0.0) / narrower if narrower > 0 else 0.0


def speed_groups(t_ns: np.ndarray, q_rad: np.ndarray, velocity_rad_s: np.ndarray) -> SpeedGroups | None:
    """One joint's slow and fast strokes over the same angles, or None where the session has no two such speeds.

    Parameters
    ----------
    t_ns : (N,) stamps, ns.
    q_rad : (N,) the joint's angle, rad.
    velocity_rad_s : (N,) its direction-of-motion velocity, rad/s.
    """
    strokes = _strokes(velocity_rad_s)
    t_s = (t_ns - t_ns[0]) * 1e-9
    speed = np.array([np.percentile(np.abs(velocity_rad_s[a:b]), 90) for a, b in strokes])
    long = np.array([t_s[b - 1] - t_s[a] >= MIN_STROKE_S for a, b in strokes], dtype=bool)
    if long.sum() < 4 * MIN_STROKES:
        return None
    duration = np.array([t_s[b - 1] - t_s[a] for a, b in strokes])
    ordered = np.sort(speed[long])
    ratios = ordered[1:] / np.maximum(ordered[:-1], 1e-12)
    gap = int(np.argmax(ratios))
    if ratios[gap] < SPLIT_RATIO:
        return None
    split = float(np.sqrt(ordered[gap] * ordered[gap + 1]))
    direction = np.array([np.sign(velocity_rad_s[a]) for a, _ in strokes])
    ranges = []
    for fast in (False, True):
        group = long & ((speed > split) == fast)
        if min(int((group & (direction > 0)).sum()), int((group & (direction < 0)).sum())) < MIN_STROKES:
            return None
        if duration[group].sum() < MIN_GROUP_SHARE * duration[long].sum():
            return None
        angles = np.concatenate([q_rad[a:b] for (a, b), g in zip(strokes, group, strict=True) if g])
        ranges.append((float(angles.min()), float(angles.max())))
    if _overlap(ranges[0], ranges[1]) < MIN_OVERLAP:
        return None
    rows = np.zeros(velocity_rad_s.size, dtype=bool)
    for (a, b), s in zip(strokes, speed, strict=True):
        rows[a:b] = s > split
    return SpeedGroups(
        fast=rows,
        slow_rad_s=float(np.median(speed[long & (speed <= split)])),
        fast_rad_s=float(np.median(speed[long & (speed > split)])),
    )


@dataclass(frozen=True, kw_only=True)
class DirectionPart:
    """The resistance to fast motion in one direction beyond that to slow motion.

    Attributes
    ----------
    part_nm : fast minus slow, beyond the model's passive terms, Nm (positive: more resistance when fast).
    std_nm : its std, Nm.
    """

    part_nm: float
    std_nm: float

    @property
    def exceeds(self) -> bool:
        """Whether the part lies more than :data:`EXCEEDS_SD` std from 0."""
        return bool(abs(self.part_nm) > EXCEEDS_SD * self.std_nm)


@dataclass(frozen=True, kw_only=True)
class SpeedSplit:
    """One joint's two-speed measurement.

    Attributes
    ----------
    joint : the joint.
    groups : its speed groups.
    parts : (positive, negative) direction of motion: each direction's speed-dependent part.
    """

    joint: str
    groups: SpeedGroups
    parts: tuple[DirectionPart, DirectionPart]

    @property
    def exceeds(self) -> bool:
        """Whether some direction shows a speed-dependent part (the static moments then come from the slow part)."""
        return any(part.exceeds for part in self.parts)

    @property
    def leading(self) -> int:
        """The index into :attr:`parts` of the direction whose part lies furthest from 0 in std."""
        z = [abs(p.part_nm) / max(p.std_nm, 1e-300) for p in self.parts]
        return int(np.argmax(z))

    def finding(self, static_from_slow: bool) -> Finding:
        """The note ``speed_dependent_resistance``: both directions' parts, the speeds, and where the static moments
        came from."""
        lead = self.parts[self.leading]
        values: dict[str, float | int | bool] = {
            "part_nm": lead.part_nm,
            "std_nm": lead.std_nm,
            "direction": 1 if self.leading == 0 else -1,
            "slow_rad_s": self.groups.slow_rad_s,
            "fast_rad_s": self.groups.fast_rad_s,
            "exceeds": self.exceeds,
            "static_from_slow": static_from_slow,
        }
        for name, part in zip(DIRECTIONS, self.parts, strict=True):
            values[f"{name}_nm"] = part.part_nm
            values[f"{name}_std_nm"] = part.std_nm
        return Finding(code=FindingCode.SPEED_DEPENDENT_RESISTANCE, where=self.joint, values=values)

    def spasticity(self) -> Finding | None:
        """Possible spasticity: more resistance to fast motion in one direction only, or None."""
        # A direction counts where its part exceeds 3 std and the floor: a few mNm beyond 3 std of a very precise
        # session is no second stretch reflex (MuJoCo's reflex left 0.3-1.1 mNm in the other direction).
        exceeding = [i for i, part in enumerate(self.parts) if part.exceeds and abs(part.part_nm) >= MIN_SPASTIC_NM]
        if len(exceeding) != 1 or self.parts[exceeding[0]].part_nm <= 0:
            return None
        part = self.parts[exceeding[0]]
        values = {
            "increase_nm": part.part_nm,
            "std_nm": part.std_nm,
            "fast_rad_s": self.groups.fast_rad_s,
            "slow_rad_s": self.groups.slow_rad_s,
            "direction": 1 if exceeding[0] == 0 else -1,
        }
        return Finding(code=FindingCode.SPASTICITY, where=self.joint, values=values)


def _part(problem: Problem, slow: Fit, joint: int, rows: np.ndarray, sign: float) -> DirectionPart:
    """The mean over ``rows`` (N,) of joint ``joint``'s torque beyond the slow part's model ``slow``, with the
    motion's ``sign``, and its std: the residual mean's HAC variance plus the slow fit's, mapped through the mean
    regressor of those rows (the two taken as independent)."""
    x, y = problem.joint_rows(joint)
    residual = sign * (y[rows] - x[rows] @ slow.values)
    part = float(residual.mean())
    mean_regressor = sign * x[rows].mean(axis=0)
    count = np.array([[float(rows.sum())]])
    noise, _ = hac_covariance(count, (residual - part)[:, None])
    variance = float(noise[0, 0]) + float(mean_regressor @ slow.covariance @ mean_regressor)
    return DirectionPart(part_nm=part, std_nm=float(np.sqrt(max(variance, 0.0))))


def _without_fast(stage: Stage, groups: dict[int, SpeedGroups]) -> tuple[np.ndarray, Problem, Fit, np.ndarray]:
    """The rows with each of ``groups``' joints' fast strokes left out of its own torque equation, the problem on
    them and its fit: the slow part's model, with its own friction transition widths (n,) (rad/s; a reflex in the
    fast strokes widens the whole session's, which lowers the slow strokes' modelled friction)."""
    rows = stage.samples.rows.copy()
    for j, found in groups.items():
        rows[:, j] &= ~found.fast
    data, passive, extras = stage.data, stage.config.passive, stage.samples.extras
    widths = stage.widths_rad_s
    problem = build_problem(data, passive, rows, widths if widths.any() else None, extras)
    fit = fit_problem(problem)
    if widths.any():
        widths = transition_widths(problem, fit, data, stage.config)[0]
        problem = build_problem(data, passive, rows, widths if widths.any() else None, extras)
        fit = fit_problem(problem)
    return rows, problem, fit, widths


def measure_speed_split(
    stage: Stage, groups: dict[int, SpeedGroups]
) -> tuple[list[SpeedSplit], tuple[np.ndarray, Problem, Fit, np.ndarray]]:
    """Each split joint's speed-dependent parts: the model fitted on the slow part (each split joint's fast strokes
    out of its own equation), and per direction the fast strokes' mean torque beyond it (:func:`_part`).

    Parameters
    ----------
    stage : the identification so far (its data, rows, passive model and friction transitions).
    groups : joint index -> its speed groups; joints whose slow strokes hold too few of their rows
        (:data:`MIN_SLOW_SHARE`) or whose fast strokes too few in a direction (:data:`MIN_FAST_ROWS`) are left out.

    Returns
    -------
    The splits, and the slow part's rows (N, n), problem, fit and friction transition widths (n,).
    """
    rows_now = stage.samples.rows
    velocity = stage.data.velocity_rad_s
    usable = {}
    for j, found in groups.items():
        fast = [rows_now[:, j] & found.fast & (sign * velocity[:, j] > 0) for sign in (1.0, -1.0)]
        slow_share = (rows_now[:, j] & ~found.fast).sum() / max(int(rows_now[:, j].sum()), 1)
        if min(int(f.sum()) for f in fast) >= MIN_FAST_ROWS and slow_share >= MIN_SLOW_SHARE:
            usable[j] = found
    if not usable:
        return [], (rows_now, stage.problem, stage.fit, stage.widths_rad_s)
    rows, problem, slow, widths = _without_fast(stage, usable)
    joints = joints_for(stage.n)
    out = []
    for j, found in usable.items():
        positive, negative = (
            _part(stage.problem, slow, j, rows_now[:, j] & found.fast & (sign * velocity[:, j] > 0), sign)
            for sign in (1.0, -1.0)
        )
        out.append(SpeedSplit(joint=joints[j], groups=found, parts=(positive, negative)))
    return out, (rows, problem, slow, widths)


def split_speeds(stage: Stage) -> Stage:
    """The step: where a joint moved over the same angles at two clearly separated speeds, its speed-dependent
    resistance is measured against the slow part's model (:func:`measure_speed_split`); a joint that shows one
    keeps its fast strokes out of its equation, so that its static moments come from the slow part."""
    if stage.problems:
        return stage
    data = stage.data
    groups = {}
    for j in range(stage.n):
        found = speed_groups(data.t_ns, data.q_rad[:, j], data.velocity_rad_s[:, j])
        if found is not None:
            groups[j] = found
    if not groups:
        return stage
    splits, slow = measure_speed_split(stage, groups)
    if not splits:
        return stage
    notes = [s.finding(s.exceeds) for s in splits]
    notes += [f for f in (s.spasticity() for s in splits) if f is not None]
    joints = joints_for(stage.n)
    exceeding = {joints.index(s.joint): s.groups for s in splits if s.exceeds}
    if not exceeding:
        return stage.apply(Outcome(notes=tuple(notes)))
    if len(exceeding) < len(splits):
        slow = _without_fast(stage, exceeding)
    rows, problem, fit, widths = slow
    samples = dataclasses.replace(stage.samples, rows=rows, problem=problem)
    stage = dataclasses.replace(stage, samples=samples, widths_rad_s=widths)
    return stage.apply(Outcome(problem=problem, fit=fit, notes=tuple(notes)))


def speed_dependence_block(findings: Iterable[Finding]) -> dict[str, Any]:
    """The estimate's ``speed_dependence`` block (docs/contract.md) from the ``speed_dependent_resistance`` notes:
    per joint measured at two speeds, the two speeds, where its static moments came from, and per direction of
    motion the speed-dependent part with its std and whether it lies beyond 3 std of 0. Empty for one speed."""
    block: dict[str, Any] = {}
    for finding in findings:
        if finding.code is not FindingCode.SPEED_DEPENDENT_RESISTANCE:
            continue
        v = finding.values
        entry: dict[str, Any] = {
            "slow_rad_s": float(v["slow_rad_s"]),
            "fast_rad_s": float(v["fast_rad_s"]),
            "static_moments_from": "slow" if v["static_from_slow"] else "session",
        }
        for name in DIRECTIONS:
            part, std = float(v[f"{name}_nm"]), float(v[f"{name}_std_nm"])
            exceeds = DirectionPart(part_nm=part, std_nm=std).exceeds
            entry[name] = {"part_nm": part, "std_nm": std, "exceeds_3_std": exceeds}
        block[finding.where] = entry
    return block
