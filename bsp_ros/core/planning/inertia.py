"""An inertia-exciting protocol: two sines per joint within the therapist's ranges, speed and acceleration limits."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bsp_ros.core.planning.planner import Plan, PlanRequest, _predict, inertial_torque_ratio, with_budget
from bsp_ros.core.planning.safety import check_reachable, check_trajectory_within
from bsp_ros.core.planning.trajectory import PlannedTrajectory
from bsp_ros.core.simulation.trajectory import MultiSineTrajectory
from bsp_ros.core.streams import joints_for
from bsp_ros.errors import InputError
from bsp_ros.validation import check_positive

# A sine's acceleration is its speed times its angular frequency, so short periods excite inertia at a bounded
# speed; a second, slower sine per joint keeps the acceleration from being proportional to the angle (a single
# sine's inertial torque looks like a stiffness or gravity). The fastest period stays at or above 2 s (0.5 Hz:
# a relaxed arm strapped to a handle, and the estimator's derivative filters, follow it).
FAST_PERIOD_MIN_S = 2.0
PERIOD_RATIO = 3.76
JOINT_PACE = (1.0, 1.29, 1.57)
PHASES_RAD = ((0.0, 1.3), (1.0, 2.9), (2.0, 0.4))
RAMP_S = 3.0
KNOT_STEP_S = 0.05
# Margins: the ramps add a little speed, and the range is not touched at its ends.
SPEED_SHARE = 0.9
RANGE_SHARE = 0.95
MAX_ACCELERATION_RAD_S2 = 5.0


def _envelope(t: np.ndarray, duration_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Raised-cosine ramps in and out (value, derivative): the motion starts and ends at rest."""
    ramp = min(RAMP_S, duration_s / 4.0)
    rising = np.clip(t / ramp, 0.0, 1.0)
    falling = np.clip((duration_s - t) / ramp, 0.0, 1.0)
    value = 0.25 * (1 - np.cos(np.pi * rising)) * (1 - np.cos(np.pi * falling))
    d_rising = np.where((t > 0) & (t < ramp), 0.5 * np.pi / ramp * np.sin(np.pi * rising), 0.0)
    inside = (duration_s - t > 0) & (duration_s - t < ramp)
    d_falling = np.where(inside, -0.5 * np.pi / ramp * np.sin(np.pi * falling), 0.0)
    derivative = d_rising * 0.5 * (1 - np.cos(np.pi * falling)) + 0.5 * (1 - np.cos(np.pi * rising)) * d_falling
    return value, derivative


def inertia_sines(request: PlanRequest, max_acceleration_rad_s2: float) -> MultiSineTrajectory:
    """The sines of each joint (two per joint, about the middle of its range), before the ramps.

    Each joint's two sines share its speed equally; the fastest joint's fast period follows from the
    acceleration limit (never below :data:`FAST_PERIOD_MIN_S`), the others run at their own pace
    (:data:`JOINT_PACE`); a joint whose range cannot hold its excursion at the speed limit moves slower.

    Raises
    ------
    InputError
        The session is too short for the slow sines (three periods at least).
    """
    accel = check_positive("largest joint acceleration (rad/s^2)", max_acceleration_rad_s2, MAX_ACCELERATION_RAD_S2)
    n = request.nominal.n_joints
    ranges = np.radians(request.usable_range_deg())
    half = 0.5 * RANGE_SHARE * (ranges[:, 1] - ranges[:, 0])
    speed = SPEED_SHARE * request.limits.max_speed_rad_s
    omega_fast = min(2.0 * accel / (speed * (1.0 + 1.0 / PERIOD_RATIO)), 2.0 * math.pi / FAST_PERIOD_MIN_S)
    omega = np.array([[omega_fast / JOINT_PACE[j], omega_fast / JOINT_PACE[j] / PERIOD_RATIO] for j in range(n)])
    slowest_s = float(2.0 * math.pi / omega.min())
    needed_s = math.ceil(3.0 * slowest_s + 2.0 * RAMP_S)
    if request.duration_s < needed_s:
        raise InputError(
            f"a {request.duration_s:g} s session is too short to excite inertia: its slowest sine takes "
            f"{slowest_s:.1f} s and needs three periods (--duration {needed_s} or more)"
        )
    reach = (1.0 / omega).sum(axis=1)  # excursion per unit speed share: amp_k = (v / 2) / omega_k
    joint_speed = np.minimum(speed, 2.0 * half / reach)
    amplitude = 0.5 * joint_speed[:, None] / omega
    return MultiSineTrajectory(
        tuple(np.degrees(ranges.mean(axis=1)).tolist()),
        tuple(tuple(row) for row in np.degrees(amplitude).tolist()),
        tuple(tuple(row) for row in (2.0 * math.pi / omega).tolist()),
        PHASES_RAD[:n],
    )


def inertia_trajectory(sines: MultiSineTrajectory, duration_s: float) -> PlannedTrajectory:
    """``sines`` ramped in and out, as knots every :data:`KNOT_STEP_S` (exact angles and velocities)."""
    t = np.append(np.arange(0.0, duration_s, KNOT_STEP_S), duration_s)
    centre = np.radians(np.asarray(sines.center_deg))
    envelope, envelope_rate = _envelope(t, duration_s)
    wave = sines.angles_rad(t) - centre
    q = centre + envelope[:, None] * wave
    qdot = envelope_rate[:, None] * wave + envelope[:, None] * sines.velocities_rad_s(t)
    qdot[0] = 0.0
    qdot[-1] = 0.0
    return PlannedTrajectory(t, q, qdot)


def plan_inertia_protocol(request: PlanRequest, max_acceleration_rad_s2: float) -> Plan:
    """An inertia-exciting plan: the two-sine motion, checked against the limits and for reachability.

    Its ``prediction`` is the quasi-static model's (static moments and passive terms); the grouped inertias'
    std comes from a simulated session (``bsp plan --excite-inertia`` prints it), as the prediction does not
    hold the inertial columns yet.
    """
    sines = inertia_sines(request, max_acceleration_rad_s2)
    trajectory = inertia_trajectory(sines, request.duration_s)
    check_trajectory_within(trajectory, request.limits)
    check_reachable(trajectory, request.nominal.lengths_m, request.shoulder_yz_m)
    periods = np.array(sines.period_s)
    amplitudes_rad = np.radians(np.array(sines.amplitude_deg))
    grid = np.linspace(0.0, request.duration_s, int(request.duration_s * 20) + 1)
    speed = np.abs(trajectory.velocities_rad_s(grid)).max(axis=0)
    accelerations = (amplitudes_rad * (2.0 * math.pi / periods) ** 2).sum(axis=1)
    notes = [
        "inertia-exciting: two sines per joint ("
        + ", ".join(f"{j} {p[0]:.1f} and {p[1]:.1f} s" for j, p in zip(joints_for(len(periods)), periods, strict=True))
        + f"), peak speeds {np.round(speed, 3).tolist()} rad/s, peak accelerations "
        f"{np.round(accelerations, 3).tolist()} rad/s^2; the stds above are the quasi-static model's"
    ]
    ratio = inertial_torque_ratio(trajectory, request.nominal)
    amplitudes = np.array(sines.amplitude_deg).sum(axis=1)
    centres = np.array(sines.center_deg)[None]
    return with_budget(
        Plan(
            request=request,
            trajectory=trajectory,
            centres_deg=centres,
            amplitudes_deg=amplitudes,
            prediction=_predict(request, trajectory),
            inertia_ratio=ratio,
            notes=notes,
        )
    )


def simulated_inertia_std(
    plan: Plan, subject: Any, *, seed: int = 0, marker_placement_sd_m: float = 0.002
) -> dict[str, tuple[float, float, str]]:
    """The grouped inertias' std a session of ``plan`` reports, from one simulated session (seeded).

    ``subject`` is the :class:`~bsp_ros.core.simulation.SubjectTruth` simulated (the table arm); the sensor is
    taken as tared, the markers' placement sd as given. Returns per segment ``(value, std, source)`` of
    ``grouped_inertia_kgm2``: a prediction by simulation, as the planner's covariance has no inertial columns.
    """
    from bsp_ros.core import simulation as sim
    from bsp_ros.core.pipeline import IdentifyOptions, identify_session
    from bsp_ros.core.planning.budget import NOMINAL_COULOMB_NM
    from bsp_ros.core.planning.simulated import plan_cell_spec

    passive = sim.PassiveTruth(coulomb_nm=NOMINAL_COULOMB_NM[: plan.request.nominal.n_joints])
    spec = plan_cell_spec(plan, subject, passive, seed=seed)
    options = IdentifyOptions(zero_sd_n=0.0, zero_sd_nm=0.0, marker_placement_sd_m=marker_placement_sd_m)
    document = identify_session(sim.simulate_cell(spec).session, options)
    found = {}
    for segment, quantities in document["segments"].items():
        q = quantities["grouped_inertia_kgm2"]
        found[segment] = (float(q["value"]), float(q["std"]), str(q["source"]))
    return found
