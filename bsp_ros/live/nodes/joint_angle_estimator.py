"""`joint_angle_estimator`: marker poses (and the robot's handle pose) -> `arm/joint_states`, causal, watched."""

from __future__ import annotations

import functools
import sys
from typing import Any

import numpy as np

from bsp_ros.core.contact_point import CONTACT_FROM_MARKER, CONTACT_FROM_ROBOT
from bsp_ros.core.streams import joints_for, markers_for, segments_for
from bsp_ros.live.online.causal_angles import CausalAnglesConfig, CausalJointAngles
from bsp_ros.live.online.contact_track import RobotContactTrack
from bsp_ros.live.runtime.cell_parameters import ANGLES_FROM_CELL, CELL_FILE, declare_with_cell
from bsp_ros.live.runtime.parameters import Param
from bsp_ros.live.runtime.qos import rclpy_qos
from bsp_ros.live.runtime.ros import RosNode, message_class
from bsp_ros.live.runtime.spin import run_node
from msg_adapters.diagnostics import (
    ERROR,
    OK,
    WARN,
    DiagnosticArraySample,
    DiagnosticStatusData,
    build_diagnostic_array,
)
from msg_adapters.joint_state import JointStateSample, build_joint_state
from msg_adapters.pose import read_pose_stamped

NAME = "joint_angle_estimator"


PARAMETERS = (
    CELL_FILE,
    Param(name="n_segments", default=3, description="2 (mechanical arm) or 3 (human arm)", lo=2, hi=3),
    Param(name="marker_hz", default=50.0, description="nominal mocap frame rate", unit="Hz", lo=1.0, hi=1000.0),
    Param(name="cutoff_hz", default=5.0, description="causal low-pass of the angles", unit="Hz", lo=0.1, hi=100.0),
    Param(
        name="direction_cutoff_hz",
        default=0.5,
        description="low-pass of the direction velocity",
        unit="Hz",
        lo=0.01,
        hi=10.0,
    ),
    Param(
        name="max_gap_s", default=0.1, description="longer marker gaps restart the filters", unit="s", lo=0.0, hi=10.0
    ),
    Param(name="stale_s", default=0.5, description="no frame for this long: stale", unit="s", lo=0.01, hi=60.0),
    Param(name="marker_topic_prefix", default="/mocap/", description="PoseStamped topics: prefix + marker name"),
    Param(
        name="handle_pose_topic",
        default="/robot/handle_pose",
        description="the robot's contact point (PoseStamped in world): once it streams, it stands for the hand marker "
        "('': ignore)",
    ),
)
# Complete frames waiting for the robot's pose after them: more than this many and the oldest is given up.
_MAX_PENDING_FRAMES = 50


class JointAngleEstimatorNode(RosNode):
    """Collects each mocap frame's markers, estimates the angles causally and publishes them.

    A frame is processed once all of its markers arrived; a newer complete frame drops older incomplete
    ones (occlusion). `arm/joint_states` are stamped by the angle filter's group delay before their frame,
    the instant the filtered angle describes, so that angles and wrench line up (an uncompensated lag
    biases the Coulomb terms). `arm/joint_angles_raw` carries each frame's unfiltered angles at the frame
    stamp (the windowed identifier filters them with zero phase, as offline); `arm/segment_lengths` the
    running-median segment lengths (JointState with segment names, position = length in m).

    Where the robot publishes its handle pose (``handle_pose_topic``), the contact point comes from it, as
    offline: from its first pose on, a frame needs every marker but the hand's and waits for the robot pose
    stamped after it, and the contact point is interpolated at the frame stamp. `arm/contact_point` (latched
    String) says which source the angles use (``hand_marker`` or ``robot_handle_pose``); the identifier
    takes the contact point's placement sd from it.
    """

    def __init__(self) -> None:
        super().__init__(NAME)
        p, _ = declare_with_cell(self, PARAMETERS, ANGLES_FROM_CELL)
        n_segments = p["n_segments"]
        self.stale_s = p["stale_s"]
        self.n = n_segments
        self.names = markers_for(n_segments)
        config = CausalAnglesConfig(
            rate_hz=p["marker_hz"],
            cutoff_hz=p["cutoff_hz"],
            direction_cutoff_hz=min(p["direction_cutoff_hz"], p["cutoff_hz"]),
            max_gap_s=p["max_gap_s"],
        )
        self.estimator = CausalJointAngles(n_segments, config)
        self.delay_ns = int(self.estimator.group_delay_s() * 1e9)
        self.frames: dict[int, dict[str, np.ndarray]] = {}
        self.last_frame_ns: int | None = None
        self.last_receive_wall_ns: int | None = None
        self.counts = {"frames": 0, "incomplete_frames": 0, "refused": 0, "frames_without_contact_point": 0}
        self.robot: RobotContactTrack | None = RobotContactTrack() if p["handle_pose_topic"] else None
        self.using_robot = False
        self.last_robot_wall_ns: int | None = None
        self.types = message_class
        estimates = rclpy_qos("estimates")
        joint_state = message_class("sensor_msgs/msg/JointState")
        self.state_pub = self.create_publisher(joint_state, "arm/joint_states", estimates)
        self.length_pub = self.create_publisher(joint_state, "arm/segment_lengths", estimates)
        self.raw_pub = self.create_publisher(joint_state, "arm/joint_angles_raw", estimates)
        self.diag_pub = self.create_publisher(
            message_class("diagnostic_msgs/msg/DiagnosticArray"), "/diagnostics", rclpy_qos("default")
        )
        self.contact_pub = self.create_publisher(
            message_class("std_msgs/msg/String"), "arm/contact_point", rclpy_qos("tf_static")
        )
        self.contact_pub.publish(message_class("std_msgs/msg/String")(data=CONTACT_FROM_MARKER))
        pose = message_class("geometry_msgs/msg/PoseStamped")
        if self.robot is not None:
            topic = p["handle_pose_topic"]
            self.create_subscription(pose, topic, self.on_robot_pose, rclpy_qos("sensor_input"))
        for name in self.names:
            self.create_subscription(
                pose,
                p["marker_topic_prefix"] + name,
                functools.partial(self.on_pose, name),
                rclpy_qos("sensor_input"),
            )
        self.last_lengths: np.ndarray | None = None
        self.create_timer(1.0, self.on_watchdog)

    def now_ns(self) -> int:
        """The node clock, ns."""
        return int(self.get_clock().now().nanoseconds)

    def on_pose(self, marker: str, msg: Any) -> None:
        """Store one marker; process the frame once complete."""
        pose = read_pose_stamped(msg)
        self.last_receive_wall_ns = self.now_ns()
        if marker == "hand" and self.using_robot:  # the robot's contact point stands for it
            return
        if not np.isfinite(pose.position_m).all() or pose.t_ns <= 0:
            self.counts["refused"] += 1
            return
        if self.last_frame_ns is not None and pose.t_ns <= self.last_frame_ns:
            if self.last_frame_ns - pose.t_ns > 1e9:  # the clock jumped back: start over
                self.estimator = CausalJointAngles(self.n, self.estimator.config)
                self.frames.clear()
                self.last_frame_ns = None
            else:
                self.counts["refused"] += 1
                return
        self.frames.setdefault(pose.t_ns, {})[marker] = pose.position_m
        self.drain()

    def on_robot_pose(self, msg: Any) -> None:
        """Store one robot handle pose; the first switches the contact point to the robot's."""
        pose = read_pose_stamped(msg)
        assert self.robot is not None  # subscribed only with a track
        if not self.robot.add(pose.t_ns, pose.position_m):
            return
        self.last_robot_wall_ns = self.now_ns()
        if not self.using_robot:
            # The hand's segment length changes with the source: the filters and the length median start over.
            self.using_robot = True
            self.estimator = CausalJointAngles(self.n, self.estimator.config)
            self.contact_pub.publish(self.types("std_msgs/msg/String")(data=CONTACT_FROM_ROBOT))
            self.get_logger().info("the robot's handle pose streams: it is the contact point, not the hand marker")
        self.drain()

    def drain(self) -> None:
        """Process the complete frames in time order, as far as their contact point is known."""
        needed = set(self.names) - {"hand"} if self.using_robot else set(self.names)
        while True:
            complete = [t for t, frame in self.frames.items() if needed <= frame.keys()]
            if not complete:
                break
            t_ns = min(complete)
            contact = None
            if self.using_robot:
                assert self.robot is not None
                if not self.robot.covers(t_ns):
                    break
                contact = self.robot.at(t_ns)
            for stamp in [s for s in self.frames if s < t_ns]:
                del self.frames[stamp]
                self.counts["incomplete_frames"] += 1
            frame = self.frames.pop(t_ns)
            if not self.using_robot:
                self.process(t_ns, frame)
            elif contact is None:  # a gap in the robot's stream around this frame
                self.counts["frames_without_contact_point"] += 1
            else:
                self.process(t_ns, {**frame, "hand": contact})
        if len(self.frames) > _MAX_PENDING_FRAMES:  # bound memory under heavy occlusion or a silent robot
            oldest = min(self.frames)
            waiting = needed <= self.frames.pop(oldest).keys()
            self.counts["frames_without_contact_point" if waiting else "incomplete_frames"] += 1

    def process(self, t_ns: int, frame: dict[str, np.ndarray]) -> None:
        """Causal angles of one complete frame -> `arm/joint_states`."""
        self.last_frame_ns = t_ns
        self.counts["frames"] += 1
        sample = self.estimator.update(t_ns, frame)
        raw, lengths = self.estimator.last_raw_q_rad, self.estimator.lengths_m
        if raw is not None and lengths is not None and self.estimator.accepted(t_ns):
            raw_state = JointStateSample(t_ns, "", joints_for(self.n), raw, np.zeros(0), np.zeros(0))
            self.raw_pub.publish(build_joint_state(self.types, raw_state))
            if self.last_lengths is None or self.counts["frames"] % 50 == 0:
                self.last_lengths = lengths
                length_state = JointStateSample(t_ns, "", segments_for(self.n), lengths, np.zeros(0), np.zeros(0))
                self.length_pub.publish(build_joint_state(self.types, length_state))
        if sample is None:
            return
        stamp = t_ns - self.delay_ns
        state = JointStateSample(stamp, "", joints_for(self.n), sample.q_rad, sample.velocity_rad_s, np.zeros(0))
        self.state_pub.publish(build_joint_state(self.types, state))

    def on_watchdog(self) -> None:
        """Publish the node's health on /diagnostics; stale when frames stopped."""
        now = self.now_ns()
        if self.last_receive_wall_ns is None:
            level, message = WARN, "waiting for markers"
        elif now - self.last_receive_wall_ns > self.stale_s * 1e9:
            level, message = ERROR, f"stale: no marker for {(now - self.last_receive_wall_ns) / 1e9:.1f} s"
        elif self.using_robot and (robot_age_s := (now - (self.last_robot_wall_ns or now)) / 1e9) > self.stale_s:
            level, message = ERROR, f"stale: no robot handle pose for {robot_age_s:.1f} s"
        else:
            level, message = OK, "tracking" + (" (contact point from the robot)" if self.using_robot else "")
        # Frames inconsistent with the rigid chain (a swapped marker, a jump no arm makes): counted, not used.
        values = {**self.counts, "rejected_frames": self.estimator.n_rejected}
        status = DiagnosticStatusData.with_values(level, f"{NAME}", message, "", values)
        self.diag_pub.publish(build_diagnostic_array(self.types, DiagnosticArraySample(now, "", (status,))))


def main(args: list[str] | None = None) -> int:
    """Console entry point (``ros2 run bsp_ros joint_angle_estimator``); ``args``: a command line like ``sys.argv``."""
    return run_node(NAME, JointAngleEstimatorNode, JointAngleEstimatorNode.__doc__ or "", PARAMETERS, args)


if __name__ == "__main__":
    sys.exit(main())
