"""A hand that slips in the handle: the contact point drifting along the hand during a session.

A hand strapped to a handle is not fixed to it: under the arm's weight it slides by millimetres to a centimetre
over a session, in a few slips of a fraction of a second or creeping. Moving the point where the force acts by
``s`` along the last segment changes every joint's torque by the same ``s * g``, with
``g = sin(phi_n) F_y - cos(phi_n) F_z`` (the force's lever about the hand's direction; :func:`slip_lever_n`).

The travel is fitted together with the arm's parameters: ``s(t)`` piecewise linear between knots a few seconds
apart (0 at the session's start), its columns ``g(t) B_k(t)`` the same at every joint. Fitted from a residual
instead, the first fit would have taken up part of the slip already, differently at each joint, and the windows
of a short session would show a bent trend (a staircase looks like no line). A slip accumulates: the travel
follows one direction (its isotonic fit explains most of its variation), where bursts of activity, tremor,
sliding skin markers or a compliant strap give travels of either sign. And it moves every joint alike: a drifting
force sensor moves each joint by its lever, the wrist (the shortest) least.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.core.identification.joint.placement_covariance import offset_names
from bsp_ros.core.identification.result import ParameterName
from bsp_ros.core.identification.stacked import Problem, augmented, reweighted_values
from bsp_ros.core.model import absolute_angles_rad, contact_lever_sums

__all__ = [
    "DETECT_KNOT_S",
    "FOLLOW_KNOT_S",
    "MIN_KNOTS",
    "MIN_MONOTONE_SHARE",
    "MIN_SLIP_M",
    "MIN_WRIST_SHARE",
    "Slip",
    "Travel",
    "contact_slip",
    "even_knots",
    "fit_travel",
    "joint_shares",
    "monotone_share",
    "monotone_travel",
    "refined_knots",
    "slip_lever_n",
    "slip_spans",
    "travel_basis",
]

# The travel's knots when a slip is looked for, s: a few seconds hold enough of the motion that the travel is
# not confounded with the arm's own terms (a 60 s session: 12 knots).
DETECT_KNOT_S = 5.0

# At most this many knots when a slip is looked for: a longer session spaces them wider (a 10-minute session: 25 s).
# Each knot is a column of the whole session's fit, so their count sets its cost (bench/README.md, `bsp identify`
# against `AnyReader`); a slip's step lies between two knots at any spacing, and a 120 s session keeps its 5 s knots.
MAX_DETECT_KNOTS = 24

# The knots the travel is followed on once found, s: a slip of half a second moves its knot's neighbours too,
# and a misfit of a few times the sensor noise is left beside a step on 5 s knots.
FOLLOW_KNOT_S = 1.25

# A knot is fitted only where some used sample lies at least this close to it (in its basis function's value: a
# fifth of the way from its neighbours).
MIN_KNOT_WEIGHT = 0.8

# A travel is judged on this many knots at least (shorter sessions: a few random values line up by chance).
MIN_KNOTS = 8

# A contact point moving less than this over the session is not named (a strap's normal play), m.
MIN_SLIP_M = 0.003

# The share of the travel's variation its monotone fit explains, at least, for a slip (the MuJoCo slipping hand:
# 0.90-1.00; activity, tremor, sliding skin, a compliant strap and the relaxed controls: 0.05-0.55).
MIN_MONOTONE_SHARE = 0.8

# The wrist's share of the travel at least this fraction of the largest joint's (a slip: 0.7-1.3 of the
# shoulder's and elbow's on the MuJoCo slipping hand; a force drift: 0.15-0.3, the wrist's lever the shortest).
MIN_WRIST_SHARE = 0.5


@dataclass(frozen=True, kw_only=True)
class Travel:
    """The contact point's travel along the hand fitted with the arm's parameters.

    Attributes
    ----------
    knots_s : (K + 1,) the knots, s from the session's start (the first at 0, where the travel is 0).
    at_knots_m : (K + 1,) the travel at the knots, m.
    travel_m : (N,) the travel at every sample, m.
    """

    knots_s: np.ndarray
    at_knots_m: np.ndarray
    travel_m: np.ndarray


@dataclass(frozen=True, kw_only=True)
class Slip:
    """What the data tell of a slipping hand.

    Attributes
    ----------
    travel : the travel on the detection knots (:data:`DETECT_KNOT_S`), or None where the session is too short
        or the chain has no hand.
    total_m : how far the contact point went from the session's start to its end, m (0 without a travel).
    monotone_share : the share of the travel's variation its monotone fit explains (0 without a travel).
    joint_share : (n,) how much of the travel each joint shows on its own (1: all of it; empty without a travel).
    """

    travel: Travel | None
    total_m: float
    monotone_share: float
    joint_share: np.ndarray

    @property
    def found(self) -> bool:
        """Whether the hand slipped: the travel is large, follows one direction, and the wrist shows it as the
        other joints do."""
        if self.travel is None or self.total_m < MIN_SLIP_M or self.monotone_share < MIN_MONOTONE_SHARE:
            return False
        wrist, largest = float(self.joint_share[-1]), float(self.joint_share.max())
        return wrist > 0.0 and wrist >= MIN_WRIST_SHARE * largest


def slip_lever_n(q_rad: np.ndarray, lengths_m: np.ndarray, tau_nm: np.ndarray) -> np.ndarray:
    """(N,) ``g``, N: the torque at every joint per metre the contact point moves along the hand. The contact
    wrench is recovered from the torques of a 3-joint chain (``tau = -J^T w``); other chains give zeros."""
    n = q_rad.shape[1]
    if n != 3:
        return np.zeros(q_rad.shape[0])
    dy, dz = contact_lever_sums(q_rad, lengths_m)
    levers = np.stack((dy, dz, np.ones_like(dy)), axis=2)
    finite = np.isfinite(tau_nm).all(axis=1)
    wrench = np.zeros((q_rad.shape[0], 3))
    wrench[finite] = np.linalg.solve(levers[finite], -tau_nm[finite, :, None])[..., 0]
    phi = absolute_angles_rad(q_rad)[:, -1]
    return np.asarray(np.sin(phi) * wrench[:, 0] - np.cos(phi) * wrench[:, 1])


def even_knots(t_ns: np.ndarray, knot_s: float) -> np.ndarray:
    """Knots (K + 1,), s from the first sample, evenly spaced about ``knot_s`` apart over the session."""
    end_s = float(t_ns[-1] - t_ns[0]) * 1e-9
    return np.linspace(0.0, end_s, max(1, round(end_s / knot_s)) + 1)


def refined_knots(travel: Travel, step_m: float, knot_s: float) -> np.ndarray:
    """``travel``'s knots with more about ``knot_s`` apart where it steps (a knot interval over which its monotone
    fit moves at least ``step_m``, and the intervals beside it: a step is placed only to within a knot): a slip
    is a step of a fraction of a second, the hand still between slips, and finer knots where it stands still would
    only take up the model's own shortfall."""
    knots = travel.knots_s
    steps = np.flatnonzero(np.abs(np.diff(_monotone_values(travel.at_knots_m))) >= step_m)
    near = np.zeros(knots.size - 1, dtype=bool)
    for k in steps:
        near[max(k - 1, 0) : k + 2] = True
    extra = [
        np.linspace(knots[k], knots[k + 1], max(1, round(float(knots[k + 1] - knots[k]) / knot_s)) + 1)[1:-1]
        for k in np.flatnonzero(near)
    ]
    return np.sort(np.concatenate([knots, *extra]))


def travel_basis(t_ns: np.ndarray, knots_s: np.ndarray) -> np.ndarray:
    """(N, K) piecewise linear functions of time on ``knots_s`` (K + 1,), s from the first sample (the first at 0,
    where the travel is 0): column ``k`` rises from 0 at knot ``k`` to 1 at knot ``k + 1`` and falls to 0 at knot
    ``k + 2`` (the last stays 1 to the end)."""
    t_s = (t_ns - t_ns[0]) * 1e-9
    unit = np.eye(knots_s.size)
    return np.column_stack([np.interp(t_s, knots_s, unit[k]) for k in range(1, knots_s.size)])


def _travel_columns(problem: Problem, lever_n: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """(N, n, K): the torque of a unit travel at each knot, the same at every joint."""
    n = problem.torque.shape[1]
    columns = lever_n[:, None] * basis
    return np.repeat(columns[:, None, :], n, axis=1)


# The markers' offsets fitted beside the travel, each with the assumed placement as its prior (precision 1 per
# assumed sd^2): a marker a few mm off its joint centre bends the torques in a pattern the travel's knots can follow
# on a fast protocol (its sines' periods near the knots' 5 s), and a contact point 2 mm off along the hand's normal
# read as a slip of the hand. Nearly free, they took up so much of a real slip on a 60 s session that it went
# unnamed (the travel's knots scattered by 5 mm); with their prior the MuJoCo slip of 10 mm reads 8.5-9.9 mm (8.0-8.7
# without them).
_OFFSET_PRIOR_PRECISION = 1.0


def _beside_offsets(problem: Problem, offsets: np.ndarray | None) -> Problem:
    """``problem`` with the markers' offset columns ``offsets`` (N, n, m; one assumed sd each) beside its own, each
    with its prior N(0, 1); ``problem`` itself where None."""
    if offsets is None:
        return problem
    m = offsets.shape[2]
    names = offset_names(m)
    return augmented(problem, offsets, names, np.zeros(m), np.full(m, _OFFSET_PRIOR_PRECISION))


def fit_travel(
    problem: Problem, lever_n: np.ndarray, t_ns: np.ndarray, knots_s: np.ndarray, offsets: np.ndarray | None = None
) -> Travel:
    """The travel on ``knots_s`` (s from the first sample, the first 0), fitted with ``problem``'s parameters (its
    reweighted least squares with the travel's columns beside them) and the markers' offsets ``offsets`` (see
    :func:`_beside_offsets`)."""
    problem = _beside_offsets(problem, offsets)
    knots = knots_s
    basis = travel_basis(t_ns, knots)
    # A knot with no used sample beside it (rows left out about it) is not fitted: the travel there is the
    # line between its neighbours.
    used = problem.rows.any(axis=1)
    fitted = np.flatnonzero(np.abs(basis[used]).max(axis=0) > MIN_KNOT_WEIGHT)
    names: list[ParameterName] = [(f"travel_{k + 1}", "hand") for k in fitted]
    wide = augmented(problem, _travel_columns(problem, lever_n, basis[:, fitted]), names)
    values = reweighted_values(wide).values[len(problem.names) :]
    at_knots = np.interp(knots, np.concatenate(([0.0], knots[fitted + 1])), np.concatenate(([0.0], values)))
    t_s = (t_ns - t_ns[0]) * 1e-9
    return Travel(knots_s=knots, at_knots_m=at_knots, travel_m=np.interp(t_s, knots, at_knots))


def _increasing_fit(values: np.ndarray) -> np.ndarray:
    """The least-squares non-decreasing fit of ``values`` (pool adjacent violators)."""
    blocks: list[list[float]] = []  # [mean, count]
    for v in values:
        blocks.append([float(v), 1.0])
        while len(blocks) > 1 and blocks[-2][0] > blocks[-1][0]:
            mean, count = blocks.pop()
            before = blocks[-1]
            before[0] = (before[0] * before[1] + mean * count) / (before[1] + count)
            before[1] += count
    return np.concatenate([np.full(int(count), mean) for mean, count in blocks])


def _monotone_values(values: np.ndarray) -> np.ndarray:
    """The least-squares fit of ``values`` that never turns back, in the direction they go, from 0."""
    fit = _increasing_fit(values) if values[-1] >= values[0] else -_increasing_fit(-values)
    return np.asarray(fit - fit[0])


def monotone_travel(travel: Travel, t_ns: np.ndarray) -> Travel:
    """``travel`` made monotone (its least-squares fit at the knots that never turns back, in the direction it
    goes): the knots' scatter around a slip's steps taken out."""
    fit = _monotone_values(travel.at_knots_m)
    t_s = (t_ns - t_ns[0]) * 1e-9
    return Travel(knots_s=travel.knots_s, at_knots_m=fit, travel_m=np.interp(t_s, travel.knots_s, fit))


def slip_spans(travel: Travel, min_step_m: float) -> tuple[tuple[float, float], ...]:
    """Where a monotone ``travel`` moves by at least ``min_step_m`` from one knot to the next: the spans (s from the
    session's start) of its slips, adjacent ones joined."""
    steps = np.abs(np.diff(travel.at_knots_m)) >= min_step_m
    spans: list[tuple[float, float]] = []
    for k in np.flatnonzero(steps):
        start, end = float(travel.knots_s[k]), float(travel.knots_s[k + 1])
        if spans and spans[-1][1] >= start:
            spans[-1] = (spans[-1][0], end)
        else:
            spans.append((start, end))
    return tuple(spans)


def monotone_share(values: np.ndarray) -> float:
    """The share of the variance of ``values`` (K,) that their monotone fit explains, in the better of the two
    directions (1: they never turn back; a few random values: well under a half)."""
    spread = float(np.var(values))
    if spread <= 0.0:
        return 0.0
    best = max(_increasing_fit(values), -_increasing_fit(-values), key=lambda f: -float(np.mean((values - f) ** 2)))
    return 1.0 - float(np.mean((values - best) ** 2)) / spread


def joint_shares(
    problem: Problem, lever_n: np.ndarray, travel_m: np.ndarray, offsets: np.ndarray | None = None
) -> np.ndarray:
    """(n,) how much of the torque ``travel_m * lever_n`` each joint shows, fitted with ``problem``'s parameters
    (and the markers' ``offsets``, :func:`_beside_offsets`) as a column of its own at each joint (1 where the joint
    shows all of it)."""
    problem = _beside_offsets(problem, offsets)
    n = problem.torque.shape[1]
    extra = np.zeros((travel_m.size, n, n))
    for j in range(n):
        extra[:, j, j] = travel_m * lever_n
    names: list[ParameterName] = [("travel_share", f"joint_{j}") for j in range(n)]
    return np.asarray(reweighted_values(augmented(problem, extra, names)).values[-n:])


def contact_slip(
    problem: Problem,
    t_ns: np.ndarray,
    lever_n: np.ndarray,
    knot_s: float = DETECT_KNOT_S,
    offsets: np.ndarray | None = None,
) -> Slip:
    """What the data of ``problem`` (sampled at ``t_ns``, with the slip's lever ``lever_n`` (N,) of
    :func:`slip_lever_n`) tell of a contact point travelling along the hand, beside the markers' ``offsets`` (N, n,
    m; :func:`_beside_offsets`), or None.

    Returns
    -------
    Slip; without a travel where the session has fewer than :data:`MIN_KNOTS` knots or no lever.
    """
    none = Slip(travel=None, total_m=0.0, monotone_share=0.0, joint_share=np.zeros(0))
    span_s = (t_ns[-1] - t_ns[0]) * 1e-9
    if span_s < MIN_KNOTS * knot_s or not lever_n.any():
        return none
    knot_s = max(knot_s, span_s / MAX_DETECT_KNOTS)
    travel = fit_travel(problem, lever_n, t_ns, even_knots(t_ns, knot_s), offsets)
    share = monotone_share(travel.at_knots_m)
    total = float(abs(travel.at_knots_m[-1]))
    if total < MIN_SLIP_M or share < MIN_MONOTONE_SHARE:
        return Slip(travel=travel, total_m=total, monotone_share=share, joint_share=np.zeros(0))
    shares = joint_shares(problem, lever_n, travel.travel_m, offsets)
    return Slip(travel=travel, total_m=total, monotone_share=share, joint_share=shares)
