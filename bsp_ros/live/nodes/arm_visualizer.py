"""`arm_visualizer`: the identified arm as markers (RViz, Foxglove), its segment frames on /tf where tf2_msgs is."""

from __future__ import annotations

import json
import sys
from typing import Any

import numpy as np

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.live.marker_messages import build_marker_array, build_segment_tf
from bsp_ros.live.online.arm_markers import arm_markers, segment_frames
from bsp_ros.live.runtime.parameters import Param, declare_parameters
from bsp_ros.live.runtime.qos import QosSpec, rclpy_qos
from bsp_ros.live.runtime.ros import RosNode, has_message, message_class
from bsp_ros.live.runtime.spin import run_node
from msg_adapters.joint_state import read_joint_state
from msg_adapters.pose import read_pose_stamped

__all__ = ["NAME", "PARAMETERS", "ArmVisualizerNode", "main"]

NAME = "arm_visualizer"
TF_TYPE = "tf2_msgs/msg/TFMessage"
MARKERS_TOPIC = "bsp/arm_markers"

PARAMETERS = (
    Param(name="n_segments", default=3, description="2 (mechanical arm) or 3 (human arm)", lo=2, hi=3),
    Param(
        name="world_frame",
        default="world",
        description="frame of the markers (the joint angles' plane is its y-z plane)",
    ),
    Param(name="rate_hz", default=10.0, description="marker (and /tf) rate", unit="Hz", lo=0.5, hi=60.0),
    Param(
        name="shoulder_topic",
        default="/mocap/shoulder",
        description="PoseStamped of the shoulder marker: where the arm is drawn ('': at shoulder_xyz_m)",
    ),
    Param(
        name="shoulder_xyz_m",
        default=[0.0, 0.0, 0.0],
        description="the shoulder in world before (or without) a shoulder marker",
        unit="m",
    ),
    Param(
        name="frame_prefix",
        default="arm_",
        description="TF child frames are <frame_prefix><segment> (e.g. arm_forearm)",
    ),
)


class ArmVisualizerNode(RosNode):
    """Draws the arm at its current posture with what the identifier knows of it, at ``rate_hz``.

    Subscribes to `arm/joint_states`, `arm/segment_lengths`, `bsp/estimate_json`, `bsp/weight_support`,
    `bsp/precision_reached` and the shoulder marker; publishes `bsp/arm_markers` (visualization_msgs/MarkerArray in
    ``world_frame``: namespaces segments, joints, com, com_std, com_range, support, verdict) and, where tf2_msgs is
    installed, each segment's frame on /tf. The markers are :func:`bsp_ros.live.online.arm_markers.arm_markers`'s.
    """

    def __init__(self) -> None:
        super().__init__(NAME)
        p = declare_parameters(self, PARAMETERS)
        self.n = p["n_segments"]
        self.world_frame = p["world_frame"]
        self.frame_prefix = p["frame_prefix"]
        self.shoulder_m = np.array(p["shoulder_xyz_m"], dtype=np.float64)
        if self.shoulder_m.shape != (3,) or not np.isfinite(self.shoulder_m).all():
            from bsp_ros.errors import InputError

            raise InputError(f"{NAME}: parameter shoulder_xyz_m must be 3 finite numbers, got {p['shoulder_xyz_m']}")
        self.q_rad: np.ndarray | None = None
        self.lengths_m: np.ndarray | None = None
        self.estimate: Estimate | None = None
        self.support_yzx: tuple[float, float, float] | None = None
        self.precision: bool | None = None
        self.types = message_class
        self.marker_pub = self.create_publisher(
            message_class("visualization_msgs/msg/MarkerArray"), MARKERS_TOPIC, rclpy_qos("default")
        )
        self.tf_pub = None
        if has_message(TF_TYPE):
            self.tf_pub = self.create_publisher(message_class(TF_TYPE), "/tf", rclpy_qos("tf"))
        else:
            self.get_logger().info(f"{TF_TYPE} is not installed: no segment frames on /tf, markers only")
        self._subscribe(p["shoulder_topic"])
        self.create_timer(1.0 / p["rate_hz"], self.on_timer)

    def _subscribe(self, shoulder_topic: str) -> None:
        joint_state = message_class("sensor_msgs/msg/JointState")
        string = message_class("std_msgs/msg/String")
        self.create_subscription(joint_state, "arm/joint_states", self.on_joint_state, rclpy_qos("state_input"))
        self.create_subscription(joint_state, "arm/segment_lengths", self.on_lengths, rclpy_qos("estimates"))
        self.create_subscription(string, "bsp/estimate_json", self.on_estimate, rclpy_qos("estimates"))
        self.create_subscription(
            message_class("geometry_msgs/msg/WrenchStamped"),
            "bsp/weight_support",
            self.on_support,
            rclpy_qos("default"),
        )
        latched = rclpy_qos(QosSpec(reliable=True, depth=1, transient_local=True))
        self.create_subscription(
            message_class("std_msgs/msg/Bool"), "bsp/precision_reached", self.on_precision, latched
        )
        if shoulder_topic:
            pose = message_class("geometry_msgs/msg/PoseStamped")
            self.create_subscription(pose, shoulder_topic, self.on_shoulder, rclpy_qos("sensor_input"))

    # -- inputs -----------------------------------------------------------------------------------------
    def on_joint_state(self, msg: Any) -> None:
        """The arm's posture (causally filtered angles)."""
        q = read_joint_state(msg).position
        if q.size == self.n and np.isfinite(q).all():
            self.q_rad = q

    def on_lengths(self, msg: Any) -> None:
        """The segment lengths from the markers."""
        lengths = read_joint_state(msg).position
        if lengths.size == self.n and np.isfinite(lengths).all() and (lengths > 0).all():
            self.lengths_m = lengths

    def on_estimate(self, msg: Any) -> None:
        """The identifier's latest estimate (masses, COMs, verdict)."""
        try:
            self.estimate = Estimate.from_json(json.loads(msg.data))
        except (ValueError, TypeError, KeyError, AttributeError) as exc:
            self.get_logger().warning(f"bsp/estimate_json: not an estimate ({exc})", throttle_duration_sec=10.0)

    def on_support(self, msg: Any) -> None:
        """The weight support on the hand."""
        self.support_yzx = (msg.wrench.force.y, msg.wrench.force.z, msg.wrench.torque.x)

    def on_precision(self, msg: Any) -> None:
        """The session's precision signal."""
        self.precision = bool(msg.data)

    def on_shoulder(self, msg: Any) -> None:
        """The shoulder marker: where the arm is drawn."""
        position = read_pose_stamped(msg).position_m
        if np.isfinite(position).all():
            self.shoulder_m = position

    # -- outputs --------------------------------------------------------------------------------------
    def on_timer(self) -> None:
        """Publish the markers (and the segment frames) once the posture and the lengths are known."""
        if self.q_rad is None or self.lengths_m is None:
            return
        stamp = int(self.get_clock().now().nanoseconds)
        specs = arm_markers(
            self.q_rad, self.lengths_m, self.shoulder_m, self.estimate, self.support_yzx, self.precision
        )
        self.marker_pub.publish(build_marker_array(self.types, specs, self.world_frame, stamp))
        if self.tf_pub is not None:
            frames = segment_frames(self.q_rad, self.lengths_m, self.shoulder_m)
            self.tf_pub.publish(build_segment_tf(self.types, frames, self.world_frame, self.frame_prefix, stamp))


def main(args: list[str] | None = None) -> int:
    """Console entry point (``ros2 run bsp_ros arm_visualizer``); ``args``: a command line like ``sys.argv``."""
    return run_node(NAME, ArmVisualizerNode, ArmVisualizerNode.__doc__ or "", PARAMETERS, args)


if __name__ == "__main__":
    sys.exit(main())
