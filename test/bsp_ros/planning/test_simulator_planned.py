"""The simulator follows a planned trajectory (the one edit in bsp_ros.simulation) and records it in its truth."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros import simulation as sim
from bsp_ros.errors import InputError
from bsp_ros.identification.data import identification_data_from_session
from bsp_ros.planning import Plan, PlannedTrajectory


def test_simulated_markers_follow_the_planned_angles(plan: Plan) -> None:
    session = sim.simulate_cell(sim.human_arm_cell(seed=1, trajectory=plan.trajectory, duration_s=60.0))
    data = identification_data_from_session(session.session)
    t_s = (data.t_ns - sim.DEFAULT_START_NS) / 1e9
    error = data.q_rad - plan.trajectory.angles_rad(t_s)
    assert np.sqrt((error**2).mean(axis=0)).max() < 1e-3  # filtered marker noise (the hand is 9 cm long)
    assert np.ptp(plan.trajectory.angles_rad(t_s), axis=0).min() > 0.3  # the joints did move along the plan


def test_truth_records_the_planned_knots_and_reads_back(plan: Plan) -> None:
    truth = sim.simulate_cell(sim.human_arm_cell(seed=1, trajectory=plan.trajectory, duration_s=10.0)).truth
    again = sim.SessionTruth.from_dict(truth.to_dict())
    assert isinstance(again.trajectory, PlannedTrajectory)
    t = np.linspace(0.0, 120.0, 301)
    np.testing.assert_array_equal(again.trajectory.angles_rad(t), plan.trajectory.angles_rad(t))


def test_a_planned_path_through_a_straight_elbow_is_refused() -> None:
    straight = PlannedTrajectory([0.0, 60.0], np.radians([[-40.0, 40.0, 0.0], [-40.0, 1.0, 0.0]]), np.zeros((2, 3)))
    with pytest.raises(InputError, match="within 5 deg of a straight or folded arm"):
        sim.human_arm_cell(trajectory=straight)


def test_the_sinusoidal_trajectory_still_works() -> None:
    spec = sim.human_arm_cell(seed=2, duration_s=5.0)
    assert isinstance(spec.trajectory, sim.TrajectorySpec)
    assert sim.simulate_cell(spec).truth.to_dict()["trajectory"]["elbow"]["center_deg"] == 29.5
