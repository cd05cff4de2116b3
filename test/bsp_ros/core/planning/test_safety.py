"""Safety: ranges and speeds are enforced, never extrapolated; handle paths are checked for reach."""

from __future__ import annotations

import math

import numpy as np
import pytest
from planning_cases import RANGES_DEG, SHOULDER_YZ_M, nominal_arm

from bsp_ros.core.planning import (
    InfeasiblePlanError,
    JointLimits,
    PlannedTrajectory,
    PlanRequest,
    check_reachable,
    check_trajectory_within,
    handle_poses_world,
    joint_angles_from_handle_poses,
    plan_protocol,
)
from bsp_ros.errors import InputError

LENGTHS = (0.29, 0.275, 0.088)


def _move(stop_deg: tuple[float, float, float], duration_s: float = 60.0) -> PlannedTrajectory:
    start = np.radians([-40.0, 50.0, 0.0])
    return PlannedTrajectory([0.0, duration_s], [start, np.radians(stop_deg)], np.zeros((2, 3)))


@pytest.mark.parametrize(
    ("ranges", "speed", "needle"),
    [
        (((-70, -10), (10, 100)), float("nan"), "speed"),
        (((-70, -10), (10, 100)), 0.0, "positive"),
        (((-70, -10), (10, 100)), 2.0, "speed"),
        (((-10, -70), (10, 100)), 0.03, "low < high"),
        (((-70, float("inf")), (10, 100)), 0.03, "shoulder range high"),
        (((-70, -10),), 0.03, "one range per joint"),
        (((-70, -10), (10, 100, 3)), 0.03, "elbow range"),
    ],
)
def test_bad_limits_are_refused_naming_the_value(ranges, speed, needle) -> None:
    with pytest.raises(InputError, match=needle):
        JointLimits(ranges, speed)


def test_a_path_beyond_a_range_is_refused_naming_joint_and_limit() -> None:
    limits = JointLimits(((-70, -10), (10, 100), (-5, 5)))
    with pytest.raises(InputError, match=r"the wrist reaches 8\.000 deg, above its limit 5 deg"):
        check_trajectory_within(_move((-40.0, 50.0, 8.0)), limits)


def test_a_path_faster_than_the_limit_is_refused() -> None:
    limits = JointLimits(RANGES_DEG, max_speed_rad_s=0.03)
    fast = _move((-20.0, 50.0, 0.0), duration_s=10.0)  # 20 deg in 10 s peaks at 0.052 rad/s
    with pytest.raises(InputError, match=r"the shoulder moves at 0\.05\d* rad/s, above the speed limit 0\.03"):
        check_trajectory_within(fast, limits)


def test_a_path_inside_the_limits_passes() -> None:
    trajectory = _move((-30.0, 60.0, 5.0))
    assert check_trajectory_within(trajectory, JointLimits(RANGES_DEG)) is trajectory


def test_an_unreachable_handle_pose_is_refused() -> None:
    far = [[1.5, 1.2, 0.0]]  # 1.5 m in front of the shoulder: beyond any arm
    with pytest.raises(InputError, match="out of reach"):
        joint_angles_from_handle_poses(far, LENGTHS, SHOULDER_YZ_M)


def test_inverse_kinematics_recovers_the_joint_angles() -> None:
    q = np.radians([[-40.0, 50.0, 10.0], [-60.0, 90.0, -15.0], [-20.0, 20.0, 0.0]])
    poses = handle_poses_world(q, LENGTHS, SHOULDER_YZ_M)
    np.testing.assert_allclose(joint_angles_from_handle_poses(poses, LENGTHS, SHOULDER_YZ_M), q, atol=1e-12)


def test_reachability_check_refuses_a_nearly_straight_elbow() -> None:
    straight = _move((-40.0, 2.0, 0.0))
    with pytest.raises(InputError, match="out of reach"):
        check_reachable(straight, LENGTHS, SHOULDER_YZ_M)


def test_elbow_range_across_a_straight_arm_is_refused() -> None:
    limits = JointLimits((RANGES_DEG[0], (-20.0, 100.0), RANGES_DEG[2]))
    with pytest.raises(InputError, match="crosses a straight arm"):
        PlanRequest(nominal=nominal_arm(), shoulder_yz_m=SHOULDER_YZ_M, limits=limits).usable_range_deg()


def test_a_session_too_short_for_the_reversals_is_refused() -> None:
    request = PlanRequest(
        nominal=nominal_arm(),
        shoulder_yz_m=SHOULDER_YZ_M,
        limits=JointLimits(RANGES_DEG),
        duration_s=20.0,
        amplitude_deg=(20, 30, 10),
        n_points=2,
    )
    with pytest.raises(InfeasiblePlanError, match="session is too short"):
        plan_protocol(request)


def test_an_amplitude_wider_than_the_range_is_refused() -> None:
    limits = JointLimits((RANGES_DEG[0], RANGES_DEG[1], (-5.0, 5.0)))
    request = PlanRequest(
        nominal=nominal_arm(), shoulder_yz_m=SHOULDER_YZ_M, limits=limits, amplitude_deg=(5.0, 5.0, 6.0)
    )
    with pytest.raises(InputError, match="wrist amplitude 6 deg does not fit"):
        plan_protocol(request)


def test_limits_for_another_chain_are_refused() -> None:
    with pytest.raises(InputError, match="2 joint ranges given for a 3-segment arm"):
        PlanRequest(nominal=nominal_arm(), shoulder_yz_m=SHOULDER_YZ_M, limits=JointLimits(RANGES_DEG[:2]))


def test_the_elbow_is_narrowed_never_widened() -> None:
    limits = JointLimits((RANGES_DEG[0], (0.0, 180.0), RANGES_DEG[2]))
    usable = PlanRequest(nominal=nominal_arm(), shoulder_yz_m=SHOULDER_YZ_M, limits=limits).usable_range_deg()
    assert tuple(usable[1]) == (5.0, 175.0)
    assert math.isclose(usable[0][0], -70.0)
