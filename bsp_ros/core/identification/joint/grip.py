"""A hand that gives in a compliant strap: joints that stick at the motion's turns, and their stretches kept out.

A hand strapped to a robot's handle is not rigid: palm tissue and the strap give millimetres and a degree or two
under the arm's weight. A joint with dry friction then stands still where the handle turns (or where another joint
takes up the motion) until the strap has loaded it past its friction, and catches up after. Markers on the arm see
the joint stand still; the torque of its friction meanwhile turns from one direction's to the other's, which no
direction of motion can tell. With a rigid grip the robot's smooth path leaves a joint still only briefly at its
own turns: for a sine of half period ``T`` and typical (peak) speed ``V``, the direction velocity stays within a dead
band ``d`` for ``2 d T / (pi V)``. A joint whose still stretches last several times that sticks.

What follows from it: a stuck joint's friction is unknown, so its stuck stretches, widened by the reach of the
direction filter (which smears the slip after a stick into the still stretch before it), are kept out of that
joint's rows; the rule that most of a joint's samples must tell the direction of motion is judged on the samples
where it did not stick.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.excitation import deadband_rad_s
from bsp_ros.core.identification.joint.stage import Outcome, Stage
from bsp_ros.core.identification.stacked import build_problem, fit_problem
from bsp_ros.core.streams import joints_for

__all__ = [
    "MIN_DWELL_RATIO",
    "MIN_MOVING_SHARE",
    "STICK_MARGIN_S",
    "Sticks",
    "direction_share",
    "find_sticks",
    "keep_out_sticks",
]

# A joint sticks where its still stretches last at least this many times a smooth turn's (median over them): on
# the MuJoCo cell a rigid grip gives 0.9-1.5 (the paper's sines, four times faster, a slipping hand up to 2.8 at a
# single stretch), the compliant strap 3-5 at the elbow and 4-10 at the wrist.
MIN_DWELL_RATIO = 2.0

# The direction filter's reach on each side of a stick, s: a quarter period of the 0.5 Hz direction cutoff (the
# span it trims at the ends of a run for the same reason).
STICK_MARGIN_S = 0.5

# A joint that moved clearly in less than this share of the session leaves too little to identify its friction,
# stuck or not (the dead band's own limit, ``min_row_share``, applies to the samples where it did not stick).
MIN_MOVING_SHARE = 0.25

# Still stretches a joint needs before its dwell is judged (one may be its only turn).
MIN_STRETCHES = 2


@dataclass(frozen=True, kw_only=True)
class Sticks:
    """Where each joint stood still longer than a smooth turn allows.

    Attributes
    ----------
    stuck : (N, n) bool, the samples kept out of each joint's rows: its sticks widened by :data:`STICK_MARGIN_S`
        (all False at a joint that does not stick).
    dwell_ratio : (n,) median duration of the joint's still stretches over a smooth turn's (NaN where not judged).
    stick_s : (n,) mean duration of the joint's sticks, s (0 where it does not stick).
    stuck_share : (n,) share of the session inside its sticks (before widening).
    """

    stuck: np.ndarray
    dwell_ratio: np.ndarray
    stick_s: np.ndarray
    stuck_share: np.ndarray

    @property
    def sticking(self) -> np.ndarray:
        """(n,) bool: the joints that stick."""
        return np.asarray(self.stick_s > 0)


def _runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and end (exclusive) indices of each run of True in ``mask`` (N,)."""
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def _half_period_s(t_s: np.ndarray, velocity: np.ndarray, moving: np.ndarray) -> float:
    """Median time between the joint's turns (sign changes of its direction velocity among the moving samples),
    s; NaN with fewer than three turns."""
    index = np.flatnonzero(moving)
    turns = np.flatnonzero(np.diff(np.sign(velocity[index])) != 0)
    if turns.size < 3:
        return float("nan")
    at = 0.5 * (t_s[index[turns]] + t_s[index[turns + 1]])
    return float(np.median(np.diff(at)))


def _turn_ratio(t_s: np.ndarray, speed: np.ndarray, deadband: float, starts: np.ndarray, ends: np.ndarray) -> float:
    """Median, over a joint's still stretches, of their duration over a smooth turn's at the acceleration the joint
    shows beside them: the speed half a stretch's length before and after it, less the dead band, over that time.
    Near 1 for any smooth motion (a sine, a sum of sines, a plan), well above it where the joint stood still and
    then caught up."""
    ratios = []
    for start, end in zip(starts, ends, strict=True):
        begin_s, end_s = t_s[start], t_s[end - 1]
        reach_s = max(0.5 * (end_s - begin_s), 1e-3)
        beside = np.interp([begin_s - reach_s, end_s + reach_s], t_s, speed)
        acceleration = max(float(beside.mean()) - deadband, 0.0) / reach_s
        ratios.append((end_s - begin_s) * acceleration / (2.0 * deadband))
    return float(np.median(ratios)) if ratios else float("nan")


def find_sticks(t_ns: np.ndarray, velocity_rad_s: np.ndarray, deadband_rad_s: np.ndarray) -> Sticks:
    """The joints' sticks from their direction velocities.

    Parameters
    ----------
    t_ns : (N,) int64 stamps, ns.
    velocity_rad_s : (N, n) direction-of-motion velocities, rad/s.
    deadband_rad_s : (n,) each joint's dead band, rad/s: at or below it the joint stands still.

    Returns
    -------
    Sticks; a joint sticks where the median of its complete still stretches (neither at the session's start nor
    end; at least :data:`MIN_STRETCHES`) lasts :data:`MIN_DWELL_RATIO` times a smooth turn's, ``2 d T / (pi V)``
    (dead band ``d``, median half period ``T`` between its turns, typical speed ``V`` the 95th percentile), and its
    sticks are those of its still stretches that last that long. None sticks unless some joint's stretches also
    last that long against the acceleration it shows beside them (:func:`_turn_ratio`): the sine's turn above is
    too short for a sum of sines (a two-sine plan reads 2.0-2.5 on it, 0.9 on this).
    """
    t_s = (t_ns - t_ns[0]) * 1e-9
    n_samples, n = velocity_rad_s.shape
    step_s = float(np.median(np.diff(t_s))) if n_samples > 1 else 0.0
    stuck = np.zeros((n_samples, n), dtype=bool)
    ratio, stick_s, share = np.full(n, np.nan), np.zeros(n), np.zeros(n)
    margin = round(STICK_MARGIN_S / step_s) if step_s > 0 else 0
    speed = np.abs(velocity_rad_s)
    turn = np.full(n, np.nan)
    for j in range(n):
        still = speed[:, j] <= deadband_rad_s[j]
        half_s = _half_period_s(t_s, velocity_rad_s[:, j], ~still)
        typical = float(np.percentile(speed[:, j], 95))
        starts, ends = _runs(still)
        inside = (starts > 0) & (ends < n_samples)
        if not np.isfinite(half_s) or typical <= 0 or inside.sum() < MIN_STRETCHES:
            continue
        smooth_s = 2.0 * deadband_rad_s[j] * half_s / (np.pi * typical)
        dwell = (ends - starts) * step_s / smooth_s
        ratio[j] = float(np.median(dwell[inside]))
        turn[j] = _turn_ratio(t_s, speed[:, j], float(deadband_rad_s[j]), starts[inside], ends[inside])
        if ratio[j] < MIN_DWELL_RATIO:
            continue
        sticks = inside & (dwell >= MIN_DWELL_RATIO)
        stick_s[j] = float(np.mean(ends[sticks] - starts[sticks])) * step_s
        share[j] = float((ends[sticks] - starts[sticks]).sum()) / n_samples
        for start, end in zip(starts[sticks], ends[sticks], strict=True):
            stuck[max(start - margin, 0) : end + margin, j] = True
    if not (turn >= MIN_DWELL_RATIO).any():
        stuck[:], stick_s[:], share[:] = False, 0.0, 0.0
    return Sticks(stuck=stuck, dwell_ratio=ratio, stick_s=stick_s, stuck_share=share)


def direction_share(rows: np.ndarray, usable: int, stuck: np.ndarray | None) -> float:
    """The share of a joint's samples that tell its direction of motion: its ``rows`` (N,) over the ``usable``
    samples less those it stuck in (``stuck`` (N,), or None); over all the usable samples where its rows are less
    than :data:`MIN_MOVING_SHARE` of them (too little is left, stuck or not)."""
    used = int(rows.sum())
    if stuck is None or not stuck.any() or used < MIN_MOVING_SHARE * usable:
        return used / max(usable, 1)
    return used / max(usable - int(stuck.sum()), 1)


def grip_finding(data: IdentificationData, sticks: Sticks) -> Finding:
    """The note of the joint that stuck most: how long it stood still at a time, how much of the session, and how
    many joints stuck."""
    worst = int(np.argmax(sticks.stuck_share))
    values = {
        "stick_s": float(sticks.stick_s[worst]),
        "stuck_percent": float(100.0 * sticks.stuck_share[worst]),
        "dwell_ratio": float(sticks.dwell_ratio[worst]),
        "n_joints": int(sticks.sticking.sum()),
    }
    return Finding(code=FindingCode.GRIP_COMPLIANT, where=joints_for(data.n_joints)[worst], values=values)


def keep_out_sticks(stage: Stage) -> Stage:
    """Where joints stick in a compliant grip (:func:`find_sticks`), their sticks are kept out of their rows and
    the model refitted; the direction rule then judges the rest (:func:`direction_share`). Needs a Coulomb term
    (without one no row is left out for its direction)."""
    config: JointConfig = stage.config
    if "coulomb" not in config.passive.terms or not config.check_activity:
        return stage
    sticks = find_sticks(stage.data.t_ns, stage.data.velocity_rad_s, deadband_rad_s(stage.data, config))
    if not sticks.sticking.any():
        return stage
    samples = stage.samples
    rows = samples.rows & ~sticks.stuck
    problem = build_problem(stage.data, config.passive, rows, None, samples.extras)
    found = grip_finding(stage.data, sticks)
    stage = dataclasses.replace(stage, stuck=sticks.stuck)
    if (rows.sum(axis=0) < len(problem.names)).any():  # too little left to fit: the direction rule says so
        return stage.apply(Outcome(notes=(found,)))
    stage = dataclasses.replace(stage, samples=dataclasses.replace(samples, rows=rows, problem=problem))
    return stage.apply(Outcome(problem=problem, fit=fit_problem(problem), notes=(found,)))
