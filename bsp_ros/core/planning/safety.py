"""Safety checks of a planned trajectory: the therapist's joint ranges, the speed limit, reachability."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.core.model import check_lengths_m
from bsp_ros.core.normalised import normalising
from bsp_ros.core.planning.trajectory import PlannedTrajectory, handle_poses_world
from bsp_ros.core.streams import joints_for
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_array, check_finite_scalar

#: The highest speed limit accepted, rad/s: far above quasi-static motion (0.03 rad/s), a guard against typos.
MAX_SPEED_LIMIT_RAD_S = 0.5
#: The elbow is kept this far from a straight or folded arm: the contact Jacobian is singular there.
ELBOW_MARGIN_DEG = 5.0
# Round-off allowed when a path is compared with its limits (rad, rad/s): far below any physical meaning.
_TOLERANCE = 1e-9


@normalising
@dataclass(frozen=True)
class JointLimits:
    """What the therapist allows: a range per joint and one speed limit.

    Attributes
    ----------
    range_deg : (n,) ``(low, high)`` per joint, deg (q1 absolute from +y, q2 and q3 relative), low < high.
    max_speed_rad_s : largest joint speed, rad/s (0 < v <= 0.5).
    """

    range_deg: tuple[tuple[float, float], ...]
    max_speed_rad_s: float = 0.03

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: each range a ``(low, high)`` tuple of floats, the speed a float."""
        if isinstance(given.range_deg, str) or len(given.range_deg) not in (2, 3):
            raise InputError(f"give one range per joint (2 or 3 joints), got {given.range_deg!r}")
        joints = joints_for(len(given.range_deg))
        ranges = tuple(check_range_deg(joint, pair) for joint, pair in zip(joints, given.range_deg, strict=True))
        speed = check_finite_scalar("max joint speed (rad/s)", given.max_speed_rad_s, 0.0, MAX_SPEED_LIMIT_RAD_S)
        if speed <= 0.0:
            raise InputError(f"max joint speed (rad/s) must be positive, got {given.max_speed_rad_s!r}")
        return {"range_deg": ranges, "max_speed_rad_s": speed}

    @property
    def n_joints(self) -> int:
        """Number of joints (2 or 3)."""
        return len(self.range_deg)

    @property
    def low_rad(self) -> np.ndarray:
        """(n,) lower limits, rad."""
        return np.radians([pair[0] for pair in self.range_deg])

    @property
    def high_rad(self) -> np.ndarray:
        """(n,) upper limits, rad."""
        return np.radians([pair[1] for pair in self.range_deg])


def check_range_deg(joint: str, pair: object) -> tuple[float, float]:
    """Return a joint range ``(low, high)`` in deg if both are finite, within +-180 deg and low < high."""
    if not isinstance(pair, Sequence | np.ndarray) or isinstance(pair, str) or len(pair) != 2:
        raise InputError(f"the {joint} range must be (low, high) in deg, got {pair!r}")
    low = check_finite_scalar(f"{joint} range low (deg)", pair[0], -180.0, 180.0)
    high = check_finite_scalar(f"{joint} range high (deg)", pair[1], -180.0, 180.0)
    if not low < high:
        raise InputError(f"the {joint} range must have low < high, got ({low!r}, {high!r}) deg")
    return low, high


def usable_elbow_range_deg(low_deg: float, high_deg: float) -> tuple[float, float]:
    """The part of an elbow range at least 5 deg from a straight or folded arm (only ever shrinks it).

    Raises
    ------
    InputError
        The range lies within 5 deg of 0 or +-180 deg everywhere, or spans a straight arm (0 deg).
    """
    if low_deg < 0.0 < high_deg:
        raise InputError(
            f"the elbow range ({low_deg!r}, {high_deg!r}) deg crosses a straight arm (0 deg): give a range on one side"
        )
    sign = 1.0 if high_deg > 0.0 else -1.0
    magnitudes = sorted((abs(low_deg), abs(high_deg)))
    lo = max(magnitudes[0], ELBOW_MARGIN_DEG)
    hi = min(magnitudes[1], 180.0 - ELBOW_MARGIN_DEG)
    if not lo < hi:
        raise InputError(
            f"the elbow range ({low_deg!r}, {high_deg!r}) deg leaves nothing {ELBOW_MARGIN_DEG:g} deg away from a "
            "straight or folded arm"
        )
    return (lo, hi) if sign > 0 else (-hi, -lo)


def check_trajectory_within(trajectory: PlannedTrajectory, limits: JointLimits) -> PlannedTrajectory:
    """Return ``trajectory`` if every joint stays inside its range and below the speed limit.

    Raises
    ------
    InputError
        Naming the joint, the value reached and the limit.
    """
    if trajectory.n_joints != limits.n_joints:
        raise InputError(f"the trajectory has {trajectory.n_joints} joints, the limits {limits.n_joints}")
    low, high = trajectory.range_rad
    for j, joint in enumerate(joints_for(limits.n_joints)):
        lo_deg, hi_deg = limits.range_deg[j]
        if low[j] < limits.low_rad[j] - _TOLERANCE:
            raise InputError(f"the {joint} reaches {math.degrees(low[j]):.3f} deg, below its limit {lo_deg:g} deg")
        if high[j] > limits.high_rad[j] + _TOLERANCE:
            raise InputError(f"the {joint} reaches {math.degrees(high[j]):.3f} deg, above its limit {hi_deg:g} deg")
        speed = trajectory.peak_speed_rad_s[j]
        if speed > limits.max_speed_rad_s + _TOLERANCE:
            raise InputError(
                f"the {joint} moves at {speed:.4g} rad/s, above the speed limit {limits.max_speed_rad_s:g} rad/s"
            )
    return trajectory


def joint_angles_from_handle_poses(
    poses_yzp: npt.ArrayLike, lengths_m: npt.ArrayLike, shoulder_yz_m: npt.ArrayLike, elbow_sign: float = 1.0
) -> np.ndarray:
    """Joint angles of a planar chain whose contact point takes the given poses (inverse kinematics).

    Parameters
    ----------
    poses_yzp : (N, 3) handle ``[y (m), z (m), pitch (rad)]`` in ``world`` (pitch unused for 2 segments).
    lengths_m : (n,) segment lengths (m).
    shoulder_yz_m : (2,) shoulder ``[y, z]`` in ``world`` (m).
    elbow_sign : +1 for a flexed elbow with q2 > 0 (docs/contract.md), -1 for q2 < 0.

    Returns
    -------
    (N, n) joint angles (rad).

    Raises
    ------
    InputError
        A pose the chain cannot reach (naming the sample, its distance and the reachable interval), or
        one that needs the elbow within 5 deg of straight or folded.
    """
    lengths = check_lengths_m(lengths_m)
    poses = check_finite_array("handle poses [y, z, pitch]", poses_yzp, (None, 3))
    shoulder = check_finite_array("shoulder [y, z] (m)", shoulder_yz_m, (2,))
    n = lengths.size
    target = poses[:, :2] - shoulder[None, :]
    if n == 3:  # the wrist sits one hand length behind the contact point along the pitch
        target = target - lengths[2] * np.column_stack((np.cos(poses[:, 2]), np.sin(poses[:, 2])))
    a1, a2 = lengths[0], lengths[1]
    distance = np.hypot(target[:, 0], target[:, 1])
    cos_q2 = (distance**2 - a1**2 - a2**2) / (2 * a1 * a2)
    limit = math.cos(math.radians(ELBOW_MARGIN_DEG))
    bad = np.flatnonzero(np.abs(cos_q2) > limit)
    if bad.size:
        i = int(bad[0])
        point = "wrist" if n == 3 else "contact point"
        raise InputError(
            f"handle pose {i} {poses[i].round(4).tolist()} is out of reach: the {point}"
            f" is {distance[i]:.4f} m from the shoulder, the chain reaches {abs(a1 - a2):.4f}..{a1 + a2:.4f} m "
            f"(keeping the elbow {ELBOW_MARGIN_DEG:g} deg from straight or folded)"
        )
    q2 = math.copysign(1.0, elbow_sign) * np.arccos(cos_q2)
    q1 = np.arctan2(target[:, 1], target[:, 0]) - np.arctan2(a2 * np.sin(q2), a1 + a2 * np.cos(q2))
    columns = [q1, q2]
    if n == 3:
        columns.append(np.angle(np.exp(1j * (poses[:, 2] - q1 - q2))))
    return np.column_stack(columns)


def check_reachable(
    trajectory: PlannedTrajectory, lengths_m: npt.ArrayLike, shoulder_yz_m: npt.ArrayLike, tolerance_m: float = 1e-6
) -> PlannedTrajectory:
    """Return ``trajectory`` if the handle path it implies is reachable by the chain and maps back to it.

    The handle poses of the path (forward kinematics) are solved back to joint angles; every pose must lie
    inside the chain's workspace away from the elbow singularities, and the round trip must agree.

    Raises
    ------
    InputError
        An unreachable pose, or a round trip that differs (naming the sample and the difference).
    """
    times = trajectory.dense_times_s()
    q = trajectory.angles_rad(times)
    poses = handle_poses_world(q, lengths_m, shoulder_yz_m)
    sign = float(np.sign(np.median(q[:, 1]))) or 1.0
    back = joint_angles_from_handle_poses(poses, lengths_m, shoulder_yz_m, sign)
    again = handle_poses_world(back, lengths_m, shoulder_yz_m)
    error = np.abs(again[:, :2] - poses[:, :2]).max(axis=1)
    if error.max() > tolerance_m:
        i = int(np.argmax(error))
        raise InputError(
            f"the handle path does not map back to the joint path at t = {times[i]:.2f} s ({error[i]:.3g} m)"
        )
    return trajectory
