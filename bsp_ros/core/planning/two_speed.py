"""Two-speed protocols: the same motion slow, then fast, so that each speed covers the same angles.

A stretch reflex resists a fast stretch, not a slow one; the relaxed joint's passive moments do not change between
a robot's slow speeds. A session that moves the arm over the same angles once slowly (below a typical reflex
threshold) and once fast (the therapist's speed limit) lets the estimator measure the speed-dependent part apart
from the passive one (``bsp_ros.core.identification.joint.speed_split``).

Two shapes: :func:`two_speed_trajectory` plays a planned trajectory time-scaled to the slow speed, then at the fast
one, reversed and forward in turn until the fast part lasts about as long as the slow one (every piece starts and
ends at rest, so the joins are smooth and the knots exact); :class:`TwoSpeedPath` plays any motion (the paper's
sines) with a time warp whose rate changes smoothly from one speed to the other at the session's middle.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from bsp_ros.core.planning.trajectory import PlannedTrajectory
from bsp_ros.core.simulation.trajectory import JointTrajectory, joint_accelerations_rad_s2
from bsp_ros.errors import InputError

if TYPE_CHECKING:
    from bsp_ros.core.planning.planner import Plan, PlanRequest

__all__ = [
    "MAX_SPEED_RATIO",
    "MIN_SPEED_RATIO",
    "TwoSpeedPath",
    "check_speeds",
    "fast_repeats",
    "plan_two_speed",
    "two_speed_trajectory",
]

# The estimator tells two speeds apart at a ratio of 2 or more; above 8 the slow part falls under its direction
# deadband (a tenth of the session's typical speed, which is the fast part's).
MIN_SPEED_RATIO = 2.0
MAX_SPEED_RATIO = 8.0


def check_speeds(slow_rad_s: float, fast_rad_s: float, max_speed_rad_s: float) -> float:
    """The ratio ``fast / slow`` of two finite positive speeds (rad/s) within the speed limit; InputError naming the
    value otherwise."""
    for name, value in (("slow", slow_rad_s), ("fast", fast_rad_s)):
        if not (math.isfinite(value) and value > 0):
            raise InputError(f"the {name} speed must be a positive number of rad/s, got {value!r}")
    if fast_rad_s > max_speed_rad_s:
        raise InputError(
            f"the fast speed {fast_rad_s:g} rad/s exceeds the speed limit {max_speed_rad_s:g} rad/s (--max-speed)"
        )
    ratio = fast_rad_s / slow_rad_s
    if not MIN_SPEED_RATIO <= ratio <= MAX_SPEED_RATIO:
        raise InputError(
            f"the fast speed must be {MIN_SPEED_RATIO:g} to {MAX_SPEED_RATIO:g} times the slow one, got "
            f"{fast_rad_s:g} / {slow_rad_s:g} = {ratio:.3g} (closer speeds cannot be told apart; a slower one falls "
            "under the estimator's direction deadband, a tenth of the fast speed)"
        )
    return ratio


def fast_repeats(ratio: float) -> int:
    """How many times the fast part plays the motion, so that it lasts about as long as the slow part."""
    return max(1, round(ratio))


def _scaled(knots: tuple[np.ndarray, np.ndarray, np.ndarray], factor: float, start_s: float, reverse: bool) -> tuple:
    """``knots`` (t, q, qdot) slowed by ``factor`` (times multiplied, speeds divided), optionally played backwards,
    shifted to begin at ``start_s``."""
    t, q, qdot = knots
    if reverse:
        t, q, qdot = t[-1] - t[::-1], q[::-1], -qdot[::-1]
    return start_s + factor * t, q, qdot / factor


def two_speed_trajectory(base: PlannedTrajectory, ratio: float) -> PlannedTrajectory:
    """``base`` (planned at the fast speed) played ``ratio`` times slower, then at its own speed reversed and
    forward in turn :func:`fast_repeats` times.

    Parameters
    ----------
    base : a planned trajectory at the fast speed (at rest at both ends).
    ratio : fast speed over slow speed (> 1).

    Returns
    -------
    PlannedTrajectory lasting ``base.duration_s * (ratio + fast_repeats(ratio))``; each piece joins the next at
    rest where both are at the same angles.
    """
    knots = base.knots
    pieces = [_scaled(knots, ratio, 0.0, False)]
    end_s = float(pieces[0][0][-1])
    for k in range(fast_repeats(ratio)):
        piece = _scaled(knots, 1.0, end_s, reverse=k % 2 == 0)
        pieces.append(tuple(a[1:] for a in piece))  # its first knot is the previous piece's last
        end_s = float(piece[0][-1])
    t = np.concatenate([p[0] for p in pieces])
    q = np.concatenate([p[1] for p in pieces])
    qdot = np.concatenate([p[2] for p in pieces])
    return PlannedTrajectory(t, q, qdot)


def plan_two_speed(
    request: PlanRequest, slow_rad_s: float, fast_rad_s: float, planner: Callable[[PlanRequest], Plan]
) -> Plan:
    """A two-speed plan: ``planner`` designs the motion at ``fast_rad_s`` for the share of the session one pass
    takes; :func:`two_speed_trajectory` plays it slow, then fast; the plan's checks and predicted stds are redone
    for the whole session.

    Parameters
    ----------
    request : what the therapist asked (its ``duration_s`` the whole session, its speed limit at least
        ``fast_rad_s``).
    slow_rad_s, fast_rad_s : the two peak joint speeds, rad/s.
    planner : :func:`~bsp_ros.core.planning.planner.plan_protocol` or another planner of the same shape.

    Raises
    ------
    InputError
        The speeds are not two clearly separated ones within the limit, or one pass does not fit the session.
    """
    from bsp_ros.core.planning.planner import _predict, inertial_torque_ratio, with_budget  # it imports this module
    from bsp_ros.core.planning.safety import JointLimits, check_reachable, check_trajectory_within

    ratio = check_speeds(slow_rad_s, fast_rad_s, request.limits.max_speed_rad_s)
    passes = ratio + fast_repeats(ratio)
    fast_limits = JointLimits(request.limits.range_deg, fast_rad_s)
    one_pass = dataclasses.replace(request, duration_s=request.duration_s / passes, limits=fast_limits)
    base = planner(one_pass)
    trajectory = two_speed_trajectory(base.trajectory, ratio)
    check_trajectory_within(trajectory, request.limits)
    check_reachable(trajectory, request.nominal.lengths_m, request.shoulder_yz_m)
    slow_s = base.trajectory.duration_s * ratio
    notes = [
        *base.notes,
        f"two speeds: {slow_s:.0f} s at {slow_rad_s:g} rad/s, then {trajectory.duration_s - slow_s:.0f} s at "
        f"{fast_rad_s:g} rad/s over the same angles (the motion played {fast_repeats(ratio)} times, reversed and "
        "forward in turn); where a joint resists the fast part more, bsp identify takes its static moments from the "
        "slow part, whose std is wider than the predicted one",
    ]
    plan = dataclasses.replace(
        base,
        request=request,
        trajectory=trajectory,
        prediction=_predict(request, trajectory),
        inertia_ratio=inertial_torque_ratio(trajectory, request.nominal),
        notes=notes,
        budget=None,
        check=None,
    )
    return with_budget(plan)


class TwoSpeedPath:
    """Any joint motion played at one rate up to the middle of the session and another after it: ``q(t) =
    base(s(t))``, the rate ``ds/dt`` changing smoothly (a smoothstep over ``ramp_s``) from ``rates[0]`` to
    ``rates[1]``. Over whole periods of a periodic ``base`` both parts cover the same angles.

    Parameters
    ----------
    base : the motion (``angles_rad``, ``velocities_rad_s``; a ``TrajectorySpec``, a planned trajectory).
    rates : (slow, fast) playback rates of ``base`` (> 0).
    switch_s : when the rate is halfway between the two, s since the session start.
    duration_s : the session length the peak speeds are taken over, s.
    ramp_s : how long the rate takes to change, s.
    """

    def __init__(
        self,
        base: JointTrajectory,
        rates: tuple[float, float],
        switch_s: float,
        duration_s: float,
        ramp_s: float = 2.0,
    ) -> None:
        if not all(math.isfinite(r) and r > 0 for r in rates) or not ramp_s > 0:
            raise InputError(f"a two-speed path needs positive rates and ramp, got {rates!r}, {ramp_s!r}")
        self.base, self.duration_s, self.ramp_s = base, duration_s, ramp_s
        self.rates = (float(rates[0]), float(rates[1]))
        self.start_s = switch_s - 0.5 * ramp_s

    @property
    def n_joints(self) -> int:
        """Number of joints (2 or 3)."""
        return self.base.n_joints

    def _phase(self, t_s: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The warped time s (N,), its rate ds/dt and the rate's derivative at ``t_s``."""
        t = np.atleast_1d(np.asarray(t_s, dtype=np.float64))
        x = (t - self.start_s) / self.ramp_s
        inside = np.clip(x, 0.0, 1.0)
        slow, fast = self.rates
        integral = np.where(x < 0, 0.0, np.where(x > 1, 0.5 + (x - 1.0), inside**3 - 0.5 * inside**4))
        s = slow * t + (fast - slow) * self.ramp_s * integral
        rate = slow + (fast - slow) * (3 * inside**2 - 2 * inside**3)
        slope = np.where((x > 0) & (x < 1), (fast - slow) / self.ramp_s * 6 * inside * (1 - inside), 0.0)
        return s, rate, slope

    @property
    def peak_speed_rad_s(self) -> tuple[float, ...]:
        """(n,) largest joint speed over the session, rad/s."""
        t = np.linspace(0.0, self.duration_s, max(int(self.duration_s * 50), 2))
        return tuple(float(v) for v in np.abs(self.velocities_rad_s(t)).max(axis=0))

    def angles_rad(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint angles at ``t_s`` (s since the session start): (N,) -> (N, n) rad."""
        return np.asarray(self.base.angles_rad(self._phase(t_s)[0]))

    def velocities_rad_s(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint velocities at ``t_s``: (N,) -> (N, n) rad/s."""
        s, rate, _ = self._phase(t_s)
        return np.asarray(self.base.velocities_rad_s(s)) * rate[:, None]

    def accelerations_rad_s2(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint accelerations at ``t_s``: (N,) -> (N, n) rad/s^2."""
        s, rate, slope = self._phase(t_s)
        base_acceleration = joint_accelerations_rad_s2(self.base, s)
        return base_acceleration * rate[:, None] ** 2 + np.asarray(self.base.velocities_rad_s(s)) * slope[:, None]
