"""The simulator follows a planned trajectory (the one edit in bsp_ros.core.simulation) and records it in its truth."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.planning import Plan, PlannedTrajectory
from bsp_ros.errors import InputError


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


@pytest.mark.dds
@pytest.mark.slow
def test_the_cell_simulator_node_follows_a_plan_file(plan: Plan, ros_domains, tmp_path) -> None:
    """`cell_simulator --ros-args -p trajectory_file:=plan.json` publishes markers along the planned angles."""
    import json
    import os
    import subprocess
    import sys

    from bsp_ros.core.planning.files import write_plan_json
    from bsp_ros.live.runtime.ros import Client
    from msg_adapters.pose import read_pose_stamped

    path = write_plan_json(tmp_path / "plan.json", plan)
    domain = ros_domains()
    client = Client("plan_listener", domain)
    markers: dict[str, dict[int, np.ndarray]] = {"shoulder": {}, "elbow": {}}
    truth: dict = {}
    for name, frames in markers.items():
        client.subscribe(
            "geometry_msgs/msg/PoseStamped",
            f"/mocap/{name}",
            lambda m, frames=frames: frames.__setitem__(read_pose_stamped(m).t_ns, read_pose_stamped(m).position_m),
            "sensor_data",
        )
    on_truth = lambda m: truth.update(json.loads(m.data))  # noqa: E731
    client.subscribe("std_msgs/msg/String", "sim/truth", on_truth, "tf_static_listener")
    node = subprocess.Popen(
        [sys.executable, "-m", "bsp_ros.live.nodes.cell_simulator", "--ros-args", "-p", f"trajectory_file:={path}"],
        env={**os.environ, "ROS_DOMAIN_ID": str(domain)},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        both = lambda: truth and len(set(markers["shoulder"]) & set(markers["elbow"])) > 100  # noqa: E731
        assert client.spin_until(both, 60), (len(markers["shoulder"]), truth.keys())
        stamps = sorted(set(markers["shoulder"]) & set(markers["elbow"]))
        upper_arm = np.array([markers["elbow"][t] - markers["shoulder"][t] for t in stamps])
        q1 = np.arctan2(upper_arm[:, 2], upper_arm[:, 1])
        planned = plan.trajectory.angles_rad((np.array(stamps) - truth["start_time_ns"]) / 1e9)[:, 0]
        assert np.abs(q1 - planned).max() < 0.01  # marker noise over a 0.3 m upper arm: well below 10 mrad
    finally:
        node.kill()
        node.wait(5)
        client.close()
