"""`arm_visualizer` on rclpy + Fast DDS: the arm a peer's joint states, lengths, shoulder marker, estimate and support
describe comes back as a MarkerArray in world, the joints where the angles put them, the COMs at the estimate's."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from node_processes import NodeProcesses, Peer

from bsp_ros.live.runtime.ros import has_message, message_class
from msg_adapters.joint_state import JointStateSample, build_joint_state
from msg_adapters.pose import PoseSample, build_pose_stamped

pytestmark = [pytest.mark.dds]

Q_RAD = np.array([-0.6, 0.9, -0.2])
LENGTHS_M = np.array([0.3, 0.27, 0.09])
SHOULDER_M = np.array([0.1, 0.2, 1.3])
ESTIMATE = {
    "method": "joint",
    "segments": {
        name: {
            "mass_kg": {"value": mass, "std": 0.2, "source": "data+prior"},
            "com_m": {"value": com, "std": 0.01, "source": "data+prior"},
        }
        for name, mass, com in (("upper_arm", 2.0, 0.17), ("forearm", 1.2, 0.12), ("hand", 0.45, 0.07))
    },
    "joints": {},
    "quality": {"valid": True, "message": "identified"},
}


def test_the_markers_draw_the_published_arm_in_world(ros_domain: int, tmp_path: Path) -> None:
    nodes = NodeProcesses(ros_domain, tmp_path)
    peer = Peer(ros_domain)
    arrays: list[Any] = []
    try:
        nodes.start("arm_visualizer", ["rate_hz:=5.0"])
        peer.client.subscribe("visualization_msgs/msg/MarkerArray", "bsp/arm_markers", arrays.append, "default")
        states = peer.client.publisher("sensor_msgs/msg/JointState", "arm/joint_states", "state_input")
        lengths = peer.client.publisher("sensor_msgs/msg/JointState", "arm/segment_lengths", "estimates")
        shoulder = peer.client.publisher("geometry_msgs/msg/PoseStamped", "/mocap/shoulder", "sensor_data")
        publish_estimate = peer.string_publisher("bsp/estimate_json")

        def publish() -> None:
            joints = ("shoulder", "elbow", "wrist")
            states.publish(
                build_joint_state(message_class, JointStateSample(1, "", joints, Q_RAD, Q_RAD * 0, Q_RAD * 0))
            )
            segments = ("upper_arm", "forearm", "hand")
            lengths.publish(
                build_joint_state(message_class, JointStateSample(1, "", segments, LENGTHS_M, np.zeros(0), np.zeros(0)))
            )
            shoulder.publish(build_pose_stamped(message_class, PoseSample(1, "world", SHOULDER_M)))
            publish_estimate(json.dumps(ESTIMATE))

        def complete() -> bool:
            publish()
            return bool(arrays) and {"com", "joints"} <= {m.ns for m in arrays[-1].markers} and _shoulder_at(arrays[-1])

        assert peer.spin_until(complete, 30), nodes.log("arm_visualizer")
    finally:
        peer.close()
        nodes.close()
    markers = {(m.ns, m.id): m for m in arrays[-1].markers}
    assert {m.header.frame_id for m in markers.values()} == {"world"}
    phi = np.cumsum(Q_RAD)
    chain = [SHOULDER_M.copy()]
    for length, angle in zip(LENGTHS_M, phi, strict=True):
        chain.append(chain[-1] + length * np.array([0.0, math.cos(angle), math.sin(angle)]))
    for k, point in enumerate(chain):
        position = markers[("joints", k)].pose.position
        np.testing.assert_allclose([position.x, position.y, position.z], point, atol=1e-9)
    for j, name in enumerate(("upper_arm", "forearm", "hand")):
        com = ESTIMATE["segments"][name]["com_m"]["value"]  # type: ignore[index]
        expected = chain[j] + com * np.array([0.0, math.cos(phi[j]), math.sin(phi[j])])
        position = markers[("com", j)].pose.position
        np.testing.assert_allclose([position.x, position.y, position.z], expected, atol=1e-9)
        assert markers[("com_std", j)].scale.x > markers[("com", j)].scale.x
    assert markers[("verdict", 0)].text == "VALID"
    assert ("support", 0) not in markers  # no weight support published


def _shoulder_at(array: Any) -> bool:
    joint = next((m for m in array.markers if m.ns == "joints" and m.id == 0), None)
    return joint is not None and abs(joint.pose.position.z - SHOULDER_M[2]) < 1e-9


@pytest.mark.skipif(has_message("tf2_msgs/msg/TFMessage"), reason="checks the install without tf2_msgs")
def test_without_tf2_msgs_the_node_says_it_publishes_markers_only(ros_domain: int, tmp_path: Path) -> None:
    nodes = NodeProcesses(ros_domain, tmp_path)
    peer = Peer(ros_domain)
    try:
        nodes.start("arm_visualizer", [])
        assert peer.spin_until(lambda: "markers only" in nodes.log("arm_visualizer"), 20), nodes.log("arm_visualizer")
    finally:
        peer.close()
        nodes.close()
