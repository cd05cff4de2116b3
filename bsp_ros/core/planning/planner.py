"""The protocol planner: operating points and direction reversals that make every parameter identifiable."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.interpolate import CubicHermiteSpline
from scipy.optimize import differential_evolution
from threadpoolctl import threadpool_limits

from bsp_ros.core.anthropometry import segment_norm
from bsp_ros.core.identification.joint import JointConfig
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.model import check_lengths_m, gravity_regressor, static_moments_kgm
from bsp_ros.core.normalised import normalising
from bsp_ros.core.planning.budget import PredictedBudget, SessionSpec, predict_budget
from bsp_ros.core.planning.information import (
    PREDICTION_GRID_HZ,
    NoiseSpec,
    NominalArm,
    Prediction,
    predict_covariance,
)
from bsp_ros.core.planning.safety import JointLimits, check_reachable, check_trajectory_within, usable_elbow_range_deg
from bsp_ros.core.planning.trajectory import PlannedTrajectory
from bsp_ros.core.streams import joints_for, segments_for
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_array, check_positive

if TYPE_CHECKING:
    from bsp_ros.core.planning.choice import AutoChoice
    from bsp_ros.core.planning.simulated import SimulatedPlanCheck

#: Given amplitudes: the default share of each joint's range, capped in deg. Optimised: the smallest.
AMPLITUDE_SHARE = 0.25
MAX_AMPLITUDE_DEG = 6.0
MIN_AMPLITUDE_DEG = 1.0
#: Ranges and amplitudes are compared with the no-motion range within this much, deg (decimal input's rounding).
_RANGE_ROUNDING_DEG = 1e-9
#: Time to reach cruise speed from rest, s. Short, because near a reversal the direction of motion (hence the
#: Coulomb sign) is uncertain: with 2 s ramps, runs of wrong signs at the wrist gave heavy-tailed errors (wrist
#: stiffness scatter 2x the prediction over 40 seeds), with 1 s none (0.9x). 0.03 rad/s in 1 s is 0.03
#: rad/s^2: the inertial torques stay below 1 % of gravity (``inertial_torque_ratio``).
RAMP_S = 1.0
#: Shortest move between reversals, s: the direction of motion is read from angles low-passed at 0.5 Hz.
MIN_MOVE_S = 4.0
#: Inertial torques above this share of the gravity torques are noted in the plan: the estimator models them
#: (rigid-body dynamics), but the predicted stds are those of the quasi-static regressor.
QUASI_STATIC_SHARE = 0.01
#: Planned speeds stay this share below the limit, so the check never rests on round-off.
_SPEED_MARGIN = 0.98
#: The objectives the planner minimises.
OBJECTIVES = ("d-optimal", "static")
# Differential evolution population per dimension, and the cost of an infeasible design (plus its excess s).
_POPULATION = 8
_INFEASIBLE = 1e3


@normalising
@dataclass(frozen=True, kw_only=True)
class PlanRequest:
    """What the planner is given.

    Attributes
    ----------
    nominal : the arm: segment lengths (measured, a previous estimate, or the anthropometric table) and the
        static moments the noise maps through (``NominalArm.from_anthropometry``).
    shoulder_yz_m : (2,) shoulder ``[y, z]`` in ``world``, m.
    limits : the therapist's range per joint (deg) and the speed limit (rad/s).
    duration_s : session length, s.
    passive : the passive model the session will identify.
    n_points : number of operating points (1-20); None tries 1, 2 and 3 and keeps the best.
    amplitude_deg : (n,) oscillation amplitude about each operating point, deg; default a quarter of each
        joint's range, at most 6 deg.
    noise : sensor noise for the predicted stds.
    objective : ``d-optimal`` (log-determinant of the predicted covariance: every parameter counts) or
        ``static`` (largest predicted relative std of the static moments).
    max_evaluations : budget of the optimiser (trajectory evaluations) per number of operating points.
    trunk_tilts_rad : the plan is recorded once per trunk posture (rad; the same motion relative to the trunk)
        and the recordings identified together: a second posture turns gravity relative to the arm.
    session : how the sessions will be identified (marker placement, sensor zero or tare): the terms of the
        predicted std beside the sensor noise (:func:`~bsp_ros.core.planning.budget.predict_budget`).
    """

    nominal: NominalArm
    shoulder_yz_m: tuple[float, float]
    limits: JointLimits
    duration_s: float = 120.0
    passive: PassiveModel = field(default_factory=lambda: PassiveModel(("coulomb", "offset", "stiffness")))
    n_points: int | None = None
    amplitude_deg: tuple[float, ...] | None = None
    noise: NoiseSpec = field(default_factory=NoiseSpec)
    objective: str = "d-optimal"
    max_evaluations: int = 400
    trunk_tilts_rad: tuple[float, ...] = (0.0,)
    session: SessionSpec = field(default_factory=SessionSpec)

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: the shoulder, the amplitudes and the tilts as tuples of floats."""
        n = given.nominal.n_joints
        if given.limits.n_joints != n:
            raise InputError(f"{given.limits.n_joints} joint ranges given for a {n}-segment arm")
        shoulder = check_finite_array("shoulder [y, z] (m)", given.shoulder_yz_m, (2,))
        out: dict[str, Any] = {"shoulder_yz_m": (float(shoulder[0]), float(shoulder[1]))}
        check_positive("session length (s)", given.duration_s, 86_400.0)
        if given.n_points is not None and (
            isinstance(given.n_points, bool) or not isinstance(given.n_points, int) or not 1 <= given.n_points <= 20
        ):
            raise InputError(f"number of operating points must be an integer within [1, 20], got {given.n_points!r}")
        if given.objective not in OBJECTIVES:
            raise InputError(f"objective must be one of {OBJECTIVES}, got {given.objective!r}")
        if given.amplitude_deg is not None:
            amplitude = check_finite_array("oscillation amplitudes (deg)", given.amplitude_deg, (n,))
            if (amplitude <= 0).any():
                raise InputError(f"oscillation amplitudes must be positive, got {amplitude.tolist()} deg")
            out["amplitude_deg"] = tuple(float(a) for a in amplitude)
        tilts = check_finite_array("trunk tilts (rad)", given.trunk_tilts_rad, (len(given.trunk_tilts_rad),))
        if not 1 <= tilts.size <= 5 or (np.abs(tilts) > np.pi / 2).any():
            raise InputError(f"one to five trunk tilts within +-90 deg, got {np.degrees(tilts).round(1).tolist()} deg")
        out["trunk_tilts_rad"] = tuple(float(t) for t in tilts)
        if not 10 <= given.max_evaluations <= 100_000:
            raise InputError(f"max_evaluations must be within [10, 100000], got {given.max_evaluations!r}")
        return out

    def usable_range_deg(self) -> np.ndarray:
        """(n, 2) the ranges the planner uses: the given ones, the elbow kept 5 deg from straight/folded."""
        ranges = np.array(self.limits.range_deg, dtype=np.float64)
        ranges[1] = usable_elbow_range_deg(*ranges[1])
        return ranges

    def amplitudes_deg(self) -> np.ndarray:
        """(n,) the oscillation amplitudes used, deg.

        Raises
        ------
        InputError
            A usable range or a given amplitude (+-amplitude) that spans less than the estimator's no-motion
            range (``JointConfig.min_range_deg``): its sessions would call the joint still.
        """
        width = np.diff(self.usable_range_deg(), axis=1)[:, 0]
        joints = joints_for(width.size)
        moving_deg = self.min_oscillation_deg()
        # within rounding: a range typed as -28.66 -28.46 is 0.2 deg wide, not 0.19999999999999929
        narrow = np.flatnonzero(width < moving_deg - _RANGE_ROUNDING_DEG)
        if narrow.size:
            j = int(narrow[0])
            raise InputError(
                f"the {joints[j]} range is {width[j]:g} deg wide: the estimator takes a joint that moves less than "
                f"{moving_deg:g} deg as still (widen the range)"
            )
        if self.amplitude_deg is None:
            return np.maximum(np.minimum(AMPLITUDE_SHARE * width, MAX_AMPLITUDE_DEG), 0.5 * moving_deg)
        amplitude = np.asarray(self.amplitude_deg)
        too_small = np.flatnonzero(2 * amplitude < moving_deg - _RANGE_ROUNDING_DEG)
        if too_small.size:
            j = int(too_small[0])
            raise InputError(
                f"the {joints[j]} amplitude {amplitude[j]:g} deg is too small: +-amplitude spans {2 * amplitude[j]:g} "
                f"deg, and the estimator takes a joint that moves less than {moving_deg:g} deg as still"
            )
        too_wide = np.flatnonzero(2 * amplitude > width)
        if too_wide.size:
            j = int(too_wide[0])
            raise InputError(
                f"the {joints[j]} amplitude {amplitude[j]:g} deg does not fit its usable range "
                f"of {width[j]:g} deg (+-amplitude about each operating point)"
            )
        return amplitude

    def min_oscillation_deg(self) -> float:
        """The smallest peak-to-peak motion a joint may make, deg: the estimator's no-motion range for the
        request's passive model (``JointConfig.min_range_deg``)."""
        return float(JointConfig(passive=self.passive).min_range_deg)


@dataclass(frozen=True, kw_only=True)
class Plan:
    """A planned protocol and what it is predicted to deliver.

    Attributes
    ----------
    request : what was asked.
    trajectory : the joint motion (checked against the limits and for reachability).
    centres_deg : (K, n) operating points, deg.
    amplitudes_deg : (n,) oscillation amplitude about each, deg.
    prediction : the sensor noise's predicted covariance (the optimiser's objective).
    inertia_ratio : (n,) largest inertial torque / largest gravity torque per joint (anthropometric inertia).
    notes : what the planner changed or assumed.
    budget : the std `bsp identify` will report, term by term (sensor noise, marker placement, sensor zero,
        model choice); None until :func:`with_budget`.
    check : with ``--passive auto``, the simulated session of the nominal arm the budget's model was chosen on
        (:func:`with_budget`); None otherwise.
    """

    request: PlanRequest
    trajectory: PlannedTrajectory
    centres_deg: np.ndarray
    amplitudes_deg: np.ndarray
    prediction: Prediction
    inertia_ratio: np.ndarray
    notes: list[str]
    budget: PredictedBudget | None = None
    check: SimulatedPlanCheck | None = None

    @property
    def auto_choice(self) -> AutoChoice | None:
        """With ``--passive auto``, the model identify chose on the nominal arm (the budget is its std); None
        otherwise."""
        return None if self.check is None else self.check.choice

    @property
    def reported(self) -> PredictedBudget:
        """The budget (:func:`with_budget` computes it where the plan has none)."""
        return self.budget if self.budget is not None else with_budget(self).reported


class InfeasiblePlanError(InputError):
    """The operating points cannot all be visited with reversals in the session at the speed limit."""

    def __init__(self, message: str, excess_s: float) -> None:
        super().__init__(message)
        self.excess_s = excess_s


def _move_time(distance: float, speed: float, ramp_s: float) -> float:
    """Shortest rest-to-rest time over ``distance`` (rad) at ``speed`` (rad/s) with ramps of ``ramp_s``.

    Never below ``MIN_MOVE_S``: the estimator's direction velocity (0.5 Hz) cannot follow faster reversals.
    """
    fastest = distance / speed + ramp_s if distance >= speed * ramp_s else 2.0 * distance / speed
    return max(fastest, MIN_MOVE_S)


def _move_knots(start: float, stop: float, t0: float, t1: float, ramp_s: float) -> list[tuple[float, float, float]]:
    """Knots ``(t, q, qdot)`` after ``t0`` of a trapezoidal move: constant acceleration, cruise, deceleration.

    A cubic Hermite piece between knots at rest and at cruise speed whose distance is that of a linear
    ramp is exactly the constant-acceleration parabola, so the knots represent the profile exactly.
    """
    duration = t1 - t0
    ramp = min(ramp_s, duration / 2.0)
    cruise = (stop - start) / (duration - ramp)
    if ramp == duration / 2.0:
        return [(t0 + ramp, 0.5 * (start + stop), cruise), (t1, stop, 0.0)]
    return [
        (t0 + ramp, start + 0.5 * cruise * ramp, cruise),
        (t1 - ramp, stop - 0.5 * cruise * ramp, cruise),
        (t1, stop, 0.0),
    ]


def _moves(centres: np.ndarray, amplitude: float, speed: float, ramp_s: float) -> tuple[np.ndarray, np.ndarray, float]:
    """Per operating point: the first oscillation end reached, and the transfer time to it; the half-cycle."""
    firsts, transfers = [], []
    here = centres[0] - amplitude
    for centre in centres:
        first = centre - amplitude if here <= centre else centre + amplitude
        firsts.append(first)
        transfers.append(_move_time(abs(first - here), speed, ramp_s) if first != here else 0.0)
        here = first  # an even number of half-cycles ends where the oscillation started
    return np.array(firsts), np.array(transfers), _move_time(2 * amplitude, speed, ramp_s)


def _joint_knots(centres: np.ndarray, amplitude: float, windows: np.ndarray, speed: float, ramp_s: float) -> np.ndarray:
    """One joint's knots: per window, move next to the operating point, then oscillate about it.

    An even number of half-cycles per window (at the speed limit, then stretched to fill the window, so
    slower, never faster); every move is trapezoidal, at rest at both ends. Returns (K, 3) ``t, q, qdot``.
    """
    firsts, transfers, half_cycle = _moves(centres, amplitude, speed, ramp_s)
    edges = np.concatenate(([0.0], np.cumsum(windows)))
    knots = [(0.0, float(firsts[0]), 0.0)]
    for k, centre in enumerate(centres):
        count = 2 * math.floor((windows[k] - transfers[k]) / (2 * half_cycle) + 1e-9)
        stretch = windows[k] / (transfers[k] + count * half_cycle)
        t = edges[k]
        if transfers[k] > 0:
            knots += _move_knots(knots[-1][1], float(firsts[k]), t, t + transfers[k] * stretch, ramp_s)
            t = knots[-1][0]
        side = -1.0 if firsts[k] < centre else 1.0
        for _ in range(count):
            side = -side
            stop = edges[k + 1] if _ == count - 1 else t + half_cycle * stretch
            knots += _move_knots(knots[-1][1], float(centre + side * amplitude), t, stop, ramp_s)
            t = stop
    return np.array(knots)


def trajectory_from_points(
    centres_rad: np.ndarray,
    amplitudes_rad: np.ndarray,
    duration_s: float,
    max_speed_rad_s: float,
    ramp_s: float = RAMP_S,
) -> PlannedTrajectory:
    """The rest-to-rest trajectory visiting operating points with oscillations about each.

    Parameters
    ----------
    centres_rad : (K, n) operating points, rad, visited in order.
    amplitudes_rad : (n,) oscillation amplitude per joint, rad.
    duration_s : session length, s.
    max_speed_rad_s : speed limit; the moves peak below it.
    ramp_s : time to reach cruise speed from rest (constant acceleration), s.

    Returns
    -------
    PlannedTrajectory whose knots are the union of the joints' own knots (each joint is cubic between
    them, so the Hermite representation is exact). Each operating point gets the time its slowest joint
    needs to reach it and reverse twice, plus an equal share of what is left.

    Raises
    ------
    InfeasiblePlanError
        The points cannot all be visited, with two reversals each, in ``duration_s``.
    """
    k_points, n = centres_rad.shape
    speed = _SPEED_MARGIN * max_speed_rad_s
    moves = [_moves(centres_rad[:, j], float(amplitudes_rad[j]), speed, ramp_s) for j in range(n)]
    needed = np.max([transfers + 2 * half for _, transfers, half in moves], axis=0)
    if needed.sum() > duration_s:
        raise InfeasiblePlanError(
            f"the session is too short: visiting {k_points} operating points with two direction reversals each at "
            f"{max_speed_rad_s:g} rad/s takes {needed.sum():.1f} s, the session has {duration_s:g} s (fewer "
            "operating points, smaller amplitudes, or a longer session)",
            float(needed.sum() - duration_s),
        )
    windows = needed + (duration_s - needed.sum()) / k_points
    per_joint = [_joint_knots(centres_rad[:, j], float(amplitudes_rad[j]), windows, speed, ramp_s) for j in range(n)]
    union = np.unique(np.concatenate([knots[:, 0] for knots in per_joint]))
    union = union[np.concatenate(([True], np.diff(union) > 1e-6))]
    q = np.empty((union.size, n))
    qdot = np.empty((union.size, n))
    for j, knots in enumerate(per_joint):
        spline = CubicHermiteSpline(knots[:, 0], knots[:, 1], knots[:, 2])
        q[:, j] = spline(np.clip(union, 0.0, knots[-1, 0]))
        qdot[:, j] = spline.derivative()(np.clip(union, 0.0, knots[-1, 0]))
    qdot[[0, -1]] = 0.0
    return PlannedTrajectory(union, q, qdot)


def _objective_value(prediction: Prediction, objective: str) -> float:
    if objective == "static":
        return math.log(prediction.max_relative_static_std)
    # D-optimality on the column-scaled covariance: invariant to units
    scale = np.sqrt(np.diag(prediction.covariance))
    sign, logdet = np.linalg.slogdet(prediction.covariance / np.outer(scale, scale))
    return float((2.0 * np.sum(np.log(scale)) + (logdet if sign > 0 else 1e3)) / scale.size)


def plan_protocol(request: PlanRequest, grid_hz: float = 2.0) -> Plan:
    """Design a trajectory that optimises identifiability within the limits, and predict its stds.

    With ``request.n_points`` None, plans with 1, 2 and 3 operating points and keeps the best objective
    (a number of points the session has no time for is skipped).

    Parameters
    ----------
    request : the subject, limits, session and noise.
    grid_hz : evaluation grid of the optimiser's predictions, Hz.

    Returns
    -------
    Plan

    Raises
    ------
    InputError
        The limits leave no room (range narrower than the oscillation, session too short), or the
        result would leave the limits or the workspace (never expected: it is checked, not assumed).
    """
    # The optimiser's covariances are small (p < 40): BLAS threads only add their start-up, which on a loaded
    # machine made `bsp plan --passive auto` several times slower (bench/README.md, plan against identify).
    with threadpool_limits(limits=1, user_api="blas"):
        if request.n_points is not None:
            return with_budget(_plan_points(request, request.n_points, grid_hz))
        plans, errors = [], []
        for k_points in (1, 2, 3):
            try:
                plans.append(_plan_points(request, k_points, grid_hz))
            except InfeasiblePlanError as error:
                errors.append(error)
        if not plans:
            raise errors[0]
        return with_budget(min(plans, key=lambda plan: _objective_value(plan.prediction, request.objective)))


def with_budget(plan: Plan) -> Plan:
    """``plan`` with the std `bsp identify` will report for its sessions, term by term (:func:`predict_budget`
    for the plan's request: its arm, model, noise, postures and session).

    With ``--passive auto`` identify reports the std of the model the data choose, widened by the spread of the
    models they cannot reject; which model that is depends on the arm. The plan is simulated once on the nominal
    arm with the cell's nonlinear, coupled passive moments (:func:`~.simulated.simulated_plan_check`) and
    identified as identify would; the budget is that model's, with the expected spread of the models left open
    there (``Plan.check`` keeps the session).
    """
    request = plan.request
    passive, check = request.passive, None
    open_models: tuple[PassiveModel, ...] = ()
    if request.passive.select:
        from bsp_ros.core.planning.simulated import nominal_subject, simulated_plan_check  # it imports this module

        check = simulated_plan_check(plan, nominal_subject(request.nominal))
        if check.choice is not None:
            passive, open_models = check.choice.chosen, check.choice.open_models
    budget = predict_budget(
        plan.trajectory,
        request.duration_s,
        request.nominal,
        passive,
        request.noise,
        request.session,
        trunk_tilts_rad=request.trunk_tilts_rad,
        open_models=open_models,
    )
    return dataclasses.replace(plan, budget=budget, check=check)


def _predict(request: PlanRequest, trajectory: PlannedTrajectory, grid_hz: float = PREDICTION_GRID_HZ) -> Prediction:
    """:func:`predict_covariance` of ``trajectory`` for the request's session, arm, model, noise and postures
    (``grid_hz``: the optimiser's coarser grid, or the reported prediction's)."""
    return predict_covariance(
        trajectory,
        request.duration_s,
        request.nominal,
        request.passive,
        request.noise,
        grid_hz=grid_hz,
        trunk_tilts_rad=request.trunk_tilts_rad,
    )


def _inertia_notes(ratio: np.ndarray) -> list[str]:
    """A note per joint whose inertial torques reach :data:`QUASI_STATIC_SHARE` of gravity (``ratio`` (n,))."""
    return [
        f"not quasi-static: inertial torques at the {joint} reach {100 * share:.2f}% of gravity (over "
        f"{100 * QUASI_STATIC_SHARE:g}%): the estimator models them and identifies the grouped inertias "
        "from them; the predicted stds above are the quasi-static model's"
        for joint, share in zip(joints_for(ratio.size), ratio, strict=True)
        if share >= QUASI_STATIC_SHARE
    ]


def _plan_points(request: PlanRequest, k_points: int, grid_hz: float) -> Plan:
    """One plan with ``k_points`` operating points.

    The amplitudes (n, unless given) and the operating points (K x n, each within its range less the
    amplitude) are optimised with scipy's differential evolution (seeded: the same request gives the same
    plan); the joints oscillate about each point at the speed limit, each at its own pace, so their motions
    are not in step.
    """
    n = request.nominal.n_joints
    ranges = np.radians(request.usable_range_deg())
    width = ranges[:, 1] - ranges[:, 0]
    # amplitudes: given, or optimised between a small wobble and half the range (one sweep end to end)
    used = np.radians(request.amplitudes_deg())  # refuses ranges and amplitudes the estimator would call still
    fixed = None if request.amplitude_deg is None else used
    # never below half the no-motion range: a smaller oscillation's sessions would call the joint still
    smallest = np.maximum(
        np.minimum(np.radians(MIN_AMPLITUDE_DEG), 0.25 * width), np.radians(0.5 * request.min_oscillation_deg())
    )
    notes = []
    given = np.array(request.limits.range_deg)
    if not np.allclose(np.degrees(ranges[1]), given[1]):
        notes.append(
            f"elbow range narrowed to {np.degrees(ranges[1]).round(2).tolist()} deg: 5 deg away from a straight or "
            "folded arm"
        )

    def decode(unit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        unit = np.clip(unit, 0.0, 1.0)
        if fixed is None:
            amplitudes = smallest + unit[:n] * (0.5 * width - smallest)
            unit = unit[n:]
        else:
            amplitudes = fixed
        low = ranges[:, 0] + amplitudes
        span = np.maximum(ranges[:, 1] - amplitudes - low, 0.0)
        return low[None, :] + unit.reshape(k_points, n) * span[None, :], amplitudes

    def build(unit: np.ndarray) -> PlannedTrajectory:
        centres, amplitudes = decode(unit)
        return trajectory_from_points(centres, amplitudes, request.duration_s, request.limits.max_speed_rad_s)

    def cost(unit: np.ndarray) -> float:
        try:
            trajectory = build(unit)
        except InfeasiblePlanError as error:
            return _INFEASIBLE + error.excess_s
        prediction = _predict(request, trajectory, grid_hz)
        value = _objective_value(prediction, request.objective)
        return value if math.isfinite(value) else _INFEASIBLE

    dims = n * k_points + (n if fixed is None else 0)
    generations = max(request.max_evaluations // (_POPULATION * dims) - 1, 1)
    result = differential_evolution(
        cost, [(0.0, 1.0)] * dims, seed=0, popsize=_POPULATION, maxiter=generations, tol=1e-4, polish=False
    )
    if result.fun >= _INFEASIBLE:
        build(result.x)  # raises the InfeasiblePlanError that names what does not fit
    best = result.x
    trajectory = build(best)
    check_trajectory_within(trajectory, request.limits)
    check_reachable(trajectory, request.nominal.lengths_m, request.shoulder_yz_m)
    centres, amplitudes = decode(best)
    prediction = _predict(request, trajectory)
    ratio = inertial_torque_ratio(trajectory, request.nominal)
    notes += _inertia_notes(ratio)
    notes.append(f"optimiser: {result.nfev} evaluations, objective {request.objective} {cost(best):.4g}")
    return Plan(
        request=request,
        trajectory=trajectory,
        centres_deg=np.degrees(centres),
        amplitudes_deg=np.degrees(amplitudes),
        prediction=prediction,
        inertia_ratio=ratio,
        notes=notes,
    )


def inertial_torque_ratio(
    trajectory: PlannedTrajectory, nominal: NominalArm, sex: str = "male", body_mass_kg: float = 75.0
) -> np.ndarray:
    """Largest inertial joint torque over the largest gravity torque, per joint, along the trajectory.

    The inertia is the anthropometric one (de Leva masses and COMs for the nominal lengths; each segment a
    uniform rod about its COM); the torque is Lagrange's ``d/dt dT/dqdot - dT/dq``.

    Returns
    -------
    (n,) ratios (quasi-static when well below 0.01).
    """
    lengths = check_lengths_m(nominal.lengths_m)
    n = lengths.size
    norms = [segment_norm(sex, name) for name in segments_for(n)]
    masses = np.array([norm.mass_fraction for norm in norms]) * body_mass_kg
    com = np.array([norm.com_fraction for norm in norms]) * lengths
    rod = masses * lengths**2 / 12.0
    t = np.linspace(0.0, trajectory.duration_s, int(trajectory.duration_s * 20) + 1)
    q = trajectory.angles_rad(t)
    qdot = trajectory.velocities_rad_s(t)

    def kinetic(angles: np.ndarray, rates: np.ndarray) -> np.ndarray:
        phi = np.cumsum(angles, axis=1)
        omega = np.cumsum(rates, axis=1)
        energy = np.zeros(angles.shape[0])
        vy = np.zeros(angles.shape[0])
        vz = np.zeros(angles.shape[0])
        for j in range(n):
            cy = vy - com[j] * omega[:, j] * np.sin(phi[:, j])
            cz = vz + com[j] * omega[:, j] * np.cos(phi[:, j])
            energy += 0.5 * masses[j] * (cy**2 + cz**2) + 0.5 * rod[j] * omega[:, j] ** 2
            vy = vy - lengths[j] * omega[:, j] * np.sin(phi[:, j])
            vz = vz + lengths[j] * omega[:, j] * np.cos(phi[:, j])
        return energy

    step = 1e-6
    momentum = np.empty_like(q)
    force = np.empty_like(q)
    for i in range(n):
        e = np.zeros(n)
        e[i] = step
        momentum[:, i] = (kinetic(q, qdot + e) - kinetic(q, qdot - e)) / (2 * step)
        force[:, i] = (kinetic(q + e, qdot) - kinetic(q - e, qdot)) / (2 * step)
    inertial = np.gradient(momentum, t, axis=0) - force
    gravity = np.einsum("tij,j->ti", gravity_regressor(q), static_moments_kgm(lengths, masses, com))
    return np.abs(inertial).max(axis=0) / np.maximum(np.abs(gravity).max(axis=0), 1e-12)
