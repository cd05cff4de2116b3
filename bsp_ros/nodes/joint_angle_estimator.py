"""`joint_angle_estimator`: marker poses -> `arm/joint_states` with causal filters and a staleness watchdog."""

from __future__ import annotations

import sys
from typing import Any

import numpy as np

from bsp_ros.online.causal_angles import CausalAnglesConfig, CausalJointAngles
from bsp_ros.runtime import run_node
from bsp_ros.streams import joints_for, markers_for, segments_for
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


class JointAngleEstimatorNode:
    """Collects each mocap frame's markers, estimates the angles causally and publishes them.

    A frame is processed once all of its markers arrived; a newer complete frame drops older incomplete
    ones (occlusion). `arm/joint_states` are stamped by the angle filter's group delay before their frame,
    the instant the filtered angle describes, so that angles and wrench line up (an uncompensated lag
    biases the Coulomb terms). `arm/joint_angles_raw` carries each frame's unfiltered angles at the frame
    stamp (the windowed identifier filters them with zero phase, as offline); `arm/segment_lengths` the
    running-median segment lengths (JointState with segment names, position = length in m).
    """

    def __init__(self, node: Any) -> None:
        self.node = node
        p = node.declare_parameter
        n_segments = p("n_segments", 3, "2 (mechanical arm) or 3 (human arm)", lo=2, hi=3)
        rate_hz = p("marker_hz", 50.0, "nominal mocap frame rate", "Hz", lo=1.0, hi=1000.0)
        cutoff_hz = p("cutoff_hz", 5.0, "causal low-pass of the angles", "Hz", lo=0.1, hi=100.0)
        direction_hz = p("direction_cutoff_hz", 0.5, "low-pass of the direction velocity", "Hz", lo=0.01, hi=10.0)
        max_gap_s = p("max_gap_s", 0.1, "longer marker gaps restart the filters", "s", lo=0.0, hi=10.0)
        self.stale_s = p("stale_s", 0.5, "no frame for this long: stale", "s", lo=0.01, hi=60.0)
        prefix = p("marker_topic_prefix", "/mocap/", "PoseStamped topics: prefix + marker name")
        self.n = n_segments
        self.names = markers_for(n_segments)
        self.estimator = CausalJointAngles(
            n_segments, CausalAnglesConfig(rate_hz, cutoff_hz, min(direction_hz, cutoff_hz), max_gap_s)
        )
        self.delay_ns = int(self.estimator.group_delay_s() * 1e9)
        self.frames: dict[int, dict[str, np.ndarray]] = {}
        self.last_frame_ns: int | None = None
        self.last_receive_wall_ns: int | None = None
        self.counts = {"frames": 0, "incomplete_frames": 0, "refused": 0}
        types = node.message_class
        self.types = types
        self.state_pub = node.create_publisher("sensor_msgs/msg/JointState", "arm/joint_states", "estimates")
        self.length_pub = node.create_publisher("sensor_msgs/msg/JointState", "arm/segment_lengths", "estimates")
        self.raw_pub = node.create_publisher("sensor_msgs/msg/JointState", "arm/joint_angles_raw", "estimates")
        self.diag_pub = node.create_publisher("diagnostic_msgs/msg/DiagnosticArray", "/diagnostics", "default")
        for name in self.names:
            node.create_subscription(
                "geometry_msgs/msg/PoseStamped", prefix + name, lambda msg, n=name: self.on_pose(n, msg), "sensor_data"
            )
        self.last_lengths: np.ndarray | None = None
        node.create_timer(1.0, self.on_watchdog)

    def on_pose(self, marker: str, msg: Any) -> None:
        """Store one marker; process the frame once complete."""
        pose = read_pose_stamped(msg)
        self.last_receive_wall_ns = self.node.now_ns()
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
        frame = self.frames.setdefault(pose.t_ns, {})
        frame[marker] = pose.position_m
        if len(frame) == len(self.names):
            for stamp in [s for s in self.frames if s < pose.t_ns]:
                del self.frames[stamp]
                self.counts["incomplete_frames"] += 1
            del self.frames[pose.t_ns]
            self.process(pose.t_ns, frame)
        elif len(self.frames) > 50:  # bound memory under heavy occlusion
            del self.frames[min(self.frames)]
            self.counts["incomplete_frames"] += 1

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
        now = self.node.now_ns()
        if self.last_receive_wall_ns is None:
            level, message = WARN, "waiting for markers"
        elif now - self.last_receive_wall_ns > self.stale_s * 1e9:
            level, message = ERROR, f"stale: no marker for {(now - self.last_receive_wall_ns) / 1e9:.1f} s"
        else:
            level, message = OK, "tracking"
        status = DiagnosticStatusData.with_values(level, f"{NAME}", message, "", self.counts)
        self.diag_pub.publish(build_diagnostic_array(self.types, DiagnosticArraySample(now, "", (status,))))


def main(args: list[str] | None = None) -> int:
    """Console entry point."""
    return run_node(JointAngleEstimatorNode, NAME, args=args)


if __name__ == "__main__":
    sys.exit(main())
