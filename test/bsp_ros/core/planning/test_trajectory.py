"""PlannedTrajectory: the TrajectorySpec interface, exact knots, rest at both ends, bad input refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bsp_ros.core.planning import PlannedTrajectory, handle_poses_world
from bsp_ros.errors import InputError


def _two_knot_move() -> PlannedTrajectory:
    return PlannedTrajectory([0.0, 10.0], [[0.0, 0.5, 0.0], [0.3, 0.8, -0.1]], np.zeros((2, 3)))


def test_angles_pass_through_the_knots_and_hold_outside() -> None:
    trajectory = _two_knot_move()
    np.testing.assert_allclose(trajectory.angles_rad([0.0, 10.0]), [[0.0, 0.5, 0.0], [0.3, 0.8, -0.1]])
    np.testing.assert_allclose(trajectory.angles_rad([-5.0, 50.0]), [[0.0, 0.5, 0.0], [0.3, 0.8, -0.1]])
    np.testing.assert_array_equal(trajectory.velocities_rad_s([-5.0, 50.0]), 0.0)


def test_velocities_are_the_derivative_of_the_angles() -> None:
    trajectory = _two_knot_move()
    t = np.linspace(0.5, 9.5, 50)
    numeric = (trajectory.angles_rad(t + 1e-5) - trajectory.angles_rad(t - 1e-5)) / 2e-5
    np.testing.assert_allclose(trajectory.velocities_rad_s(t), numeric, atol=1e-8)


def test_peak_speed_of_a_rest_to_rest_cubic_is_one_and_a_half_times_the_mean() -> None:
    trajectory = _two_knot_move()
    np.testing.assert_allclose(trajectory.peak_speed_rad_s, [1.5 * 0.03, 1.5 * 0.03, 1.5 * 0.01], rtol=1e-3)


@pytest.mark.parametrize(
    ("t", "q", "qdot", "needle"),
    [
        ([0.0, float("nan")], [[0, 0], [1, 1]], [[0, 0], [0, 0]], "knot times"),
        ([0.0, 1.0, 1.0], [[0, 0], [1, 1], [2, 2]], [[0, 0], [0, 0], [0, 0]], "increase strictly"),
        ([1.0, 2.0], [[0, 0], [1, 1]], [[0, 0], [0, 0]], "t = 0"),
        ([0.0, 1.0], [[0, 0], [1, 1]], [[0.1, 0], [0, 0]], "at rest"),
        ([0.0, 1.0], [[0], [1]], [[0], [0]], "2 or 3 joints"),
    ],
)
def test_bad_knots_are_refused_naming_the_problem(t, q, qdot, needle) -> None:
    with pytest.raises(InputError, match=needle):
        PlannedTrajectory(t, q, qdot)


def test_handle_pose_of_a_known_configuration() -> None:
    # upper arm straight down, forearm horizontal forward, hand pitched up 30 deg
    q = [[-math.pi / 2, math.pi / 2, math.radians(30.0)]]
    poses = handle_poses_world(q, [0.3, 0.25, 0.1], [0.1, 1.2])
    expected_y = 0.1 + 0.25 + 0.1 * math.cos(math.radians(30.0))
    expected_z = 1.2 - 0.3 + 0.1 * math.sin(math.radians(30.0))
    np.testing.assert_allclose(poses, [[expected_y, expected_z, math.radians(30.0)]], atol=1e-12)


def test_dict_round_trip_is_exact() -> None:
    trajectory = _two_knot_move()
    again = PlannedTrajectory.from_dict(trajectory.to_dict())
    t = np.linspace(0, 10, 33)
    np.testing.assert_array_equal(again.angles_rad(t), trajectory.angles_rad(t))
