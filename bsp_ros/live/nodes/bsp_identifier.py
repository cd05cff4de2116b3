"""`bsp_identifier`: wrench, joint states, wrench frame -> live estimates of segment parameters and passive moments."""

from __future__ import annotations

import sys
from dataclasses import replace
from functools import partial
from typing import Any

import numpy as np

from bsp_ros.core.contact_point import CONTACT_FROM_ROBOT
from bsp_ros.core.findings import FindingCode
from bsp_ros.core.streams import segments_for
from bsp_ros.core.weight_support import live_support
from bsp_ros.live.nodes import estimate_jobs as jobs
from bsp_ros.live.online.frame_notices import FrameNotices, stated_rotation
from bsp_ros.live.online.frames import WrenchFrames, WrenchQueue
from bsp_ros.live.online.identifier_modes import ModeEstimate
from bsp_ros.live.online.identifier_settings import NAME, PARAMETERS, IdentifierSettings
from bsp_ros.live.online.live_identifier import LiveIdentifier
from bsp_ros.live.online.precision import PrecisionState, PrecisionTracker
from bsp_ros.live.runtime.cell_parameters import IDENTIFIER_FROM_CELL, declare_with_cell
from bsp_ros.live.runtime.qos import QosSpec, rclpy_qos
from bsp_ros.live.runtime.ros import RosNode, has_message, message_class
from bsp_ros.live.runtime.spin import run_node
from msg_adapters.diagnostics import (
    ERROR,
    OK,
    WARN,
    DiagnosticArraySample,
    DiagnosticStatusData,
    build_diagnostic_array,
)
from msg_adapters.emg import EMG_TYPE, read_envelope
from msg_adapters.joint_state import JointStateSample, build_joint_state, read_joint_state
from msg_adapters.tf import read_tf_message, read_transform_stamped
from msg_adapters.wrench import WrenchSample, build_wrench_stamped, read_wrench_stamped

__all__ = ["NAME", "PARAMETERS", "BspIdentifierNode", "main"]

TF_TYPE = "tf2_msgs/msg/TFMessage"

# Invalid estimates that wait for a session to start (a warning on /diagnostics, not an error).
WAITING = frozenset({FindingCode.INPUT_WAITING, FindingCode.WAITING_FOR_CHECK})
# bsp/precision_reached: latched (reliable, transient local, depth 1), so session logic that starts later reads it.
LATCHED = QosSpec(reliable=True, depth=1, transient_local=True)


class BspIdentifierNode(RosNode):
    """Identifies online, in a sliding window (default) or recursively, and publishes the estimates.

    An estimate is published invalid (level ERROR) when an input is stale (nothing received for
    ``stale_s`` of wall time), and samples that are non-finite, out of order or duplicated never enter it.
    The callbacks adapt messages and hand them to the online blocks (``bsp_ros.live.online``).
    """

    def __init__(self) -> None:
        super().__init__(NAME)
        values, self.cell = declare_with_cell(self, PARAMETERS, IDENTIFIER_FROM_CELL)
        self.settings = settings = IdentifierSettings.from_parameters(values)
        self.frame_source = settings.frame_source(has_message(TF_TYPE))
        self.frames = WrenchFrames(
            settings.world_frame,
            self.frame_source.transforms,
            settings.wrench_frame_rotation,
            settings.tf_wait_s,
            transform_source="topic" if self.frame_source.topic else "tf",
        )
        self.wrench_queue = WrenchQueue(self.frames)  # a turning sensor's wrench waits for the /tf after it
        stated = stated_rotation(settings.wrench_frame_rotation_xyzw, self.cell)
        self.frame_notices = FrameNotices(self.frame_source.description, stated)
        # Every estimate is computed in the timer's callback, on the executor thread: an update (a refit of the
        # model its last check chose, or the check itself every elastic_check_every updates) is short beside the
        # timer's period, and the wrenches wait in their subscription's queue (1 s deep) and are taken right after
        # it. Not on a worker thread: it would trade the interpreter lock with the callbacks and make the update
        # itself slower (bench/README.md, live window update and live latency).
        target = settings.precision_target
        self.precision = PrecisionTracker(target) if target is not None else None
        self.precision_state: PrecisionState | None = None
        self.precision_sent: bool | None = None
        # A rotation that stood in for a missing transform, or a transform off the cell's: in every estimate.
        frame_findings = partial(self.frame_notices.findings, self.frames)
        self.identifier = LiveIdentifier(settings, self._outputs, self.get_logger().error, frame_findings)
        self.support_estimate: dict[str, Any] | None = None  # set with each estimate
        self.support_diagnostics: dict[str, str] = {}
        self.published = 0
        self._log_settings()
        self.types = message_class
        self._create_publishers()
        self._create_subscriptions()
        self.create_timer(1.0 / settings.update_hz, self.on_update)

    def _log_settings(self) -> None:
        """Where the wrench frame's rotation comes from, the tare and the wrench delay, once at start."""
        settings, logger = self.settings, self.get_logger()
        stated = f"{self.frame_notices.stated} = {list(settings.wrench_frame_rotation_xyzw)}"
        logger.info(
            f"wrench frame rotation from {self.frame_source.description}"
            + (f"; where none comes within tf_wait_s, {stated}" if self.frame_source.transforms else f": {stated}")
        )
        tare = settings.options.tare
        if tare is not None:
            logger.info(f"tare {settings.tare_file} of frame {tare.frame_id!r} applied to every wrench")
        logger.info(f"wrench delay: {settings.wrench_delay_note}")

    def _create_publishers(self) -> None:
        estimates = rclpy_qos("estimates")
        diagnostics = message_class("diagnostic_msgs/msg/DiagnosticArray")
        self.estimate_pub = self.create_publisher(diagnostics, "bsp/estimate", estimates)
        self.json_pub = self.create_publisher(message_class("std_msgs/msg/String"), "bsp/estimate_json", estimates)
        self.passive_pub = self.create_publisher(
            message_class("sensor_msgs/msg/JointState"), "bsp/passive_moments", estimates
        )
        self.inertia_pubs = {
            s: self.create_publisher(message_class("geometry_msgs/msg/InertiaStamped"), f"bsp/{s}/inertia", estimates)
            for s in segments_for(self.settings.n_segments)
        }
        self.support_pub = self.create_publisher(
            message_class("geometry_msgs/msg/WrenchStamped"), "bsp/weight_support", rclpy_qos("default")
        )
        self.diag_pub = self.create_publisher(diagnostics, "/diagnostics", rclpy_qos("default"))
        if self.precision is not None:
            boolean = message_class("std_msgs/msg/Bool")
            self.precision_pub = self.create_publisher(boolean, "bsp/precision_reached", rclpy_qos(LATCHED))
            self._publish_precision(False)

    def _create_subscriptions(self) -> None:
        settings = self.settings
        joint_state = message_class("sensor_msgs/msg/JointState")
        wrench = message_class("geometry_msgs/msg/WrenchStamped")
        self.create_subscription(wrench, settings.wrench_topic, self.on_wrench, rclpy_qos("sensor_input"))
        # The causal joint states only where they are used (each message costs the executor thread its
        # deserialisation); the unfiltered angles always: they fill the window, the windowed mode's estimate and the
        # recursive mode's model checks.
        states = rclpy_qos("state_input")
        if self.identifier.mode.takes_joint_states or settings.support_fraction > 0.0:
            self.create_subscription(joint_state, "arm/joint_states", self.on_joint_state, states)
        self.create_subscription(joint_state, "arm/joint_angles_raw", self.on_raw_angles, states)
        self.create_subscription(joint_state, "arm/segment_lengths", self.on_lengths, rclpy_qos("estimates"))
        self.create_subscription(
            message_class("std_msgs/msg/String"), "arm/contact_point", self.on_contact_point, rclpy_qos("tf_static")
        )
        if self.frame_source.tf:
            tf = message_class(TF_TYPE)
            self.create_subscription(tf, "/tf_static", self.on_tf_static, rclpy_qos("tf_static_listener"))
            self.create_subscription(tf, "/tf", self.on_tf, rclpy_qos("tf"))
        if self.frame_source.topic:
            transform = message_class("geometry_msgs/msg/TransformStamped")
            self.create_subscription(transform, settings.wrench_frame_topic, self.on_transform, rclpy_qos("tf"))
        if settings.emg_topic:  # optional: a cell without EMG sends nothing on it
            self.create_subscription(
                message_class(EMG_TYPE), settings.emg_topic, self.on_emg, rclpy_qos("sensor_input")
            )

    def now_ns(self) -> int:
        """The node clock (system time unless ``use_sim_time``), ns."""
        return int(self.get_clock().now().nanoseconds)

    # -- inputs ---------------------------------------------------------------------------------------
    def on_tf_static(self, msg: Any) -> None:
        """Fixed transforms (/tf_static)."""
        self._restart_on(self.frames.on_transforms(read_tf_message(msg), static=True))

    def on_tf(self, msg: Any) -> None:
        """Stamped transforms (/tf): a turning sensor's rotation is taken at each wrench's stamp; the wrenches
        that waited for this transform go in now."""
        self._restart_on(self.frames.on_transforms(read_tf_message(msg)))
        self._add_wrenches(self.wrench_queue.release(self.now_ns()))

    def on_transform(self, msg: Any) -> None:
        """One stamped transform of the wrench frame (``wrench_frame_source`` topic), handled as a /tf sample."""
        self._restart_on(self.frames.on_transforms([read_transform_stamped(msg)]))
        self._add_wrenches(self.wrench_queue.release(self.now_ns()))

    def _restart_on(self, changed: list[str]) -> None:
        """A fixed wrench rotation that changed restarts the estimate."""
        for frame_id in changed:
            # Samples already buffered were rotated the old way: they must not mix with new ones.
            self.get_logger().warning(f"transform of {frame_id} changed: estimate restarted")
            self.identifier.reset()
            self._restart_precision()

    def on_contact_point(self, msg: Any) -> None:
        """Where the angles' contact point comes from (`joint_angle_estimator`): the robot's handle pose holds
        the robot's registration sd in the estimate, a skin marker the marker placement sd."""
        if self.identifier.set_contact_from_robot(msg.data == CONTACT_FROM_ROBOT):
            self.get_logger().info(f"contact point: {msg.data}; estimate restarted")
            self._restart_precision()

    def on_lengths(self, msg: Any) -> None:
        """Segment lengths from the joint angle estimator."""
        self.identifier.add_lengths(read_joint_state(msg).position)

    def on_raw_angles(self, msg: Any) -> None:
        """Unfiltered joint angles: the window filters them with zero phase, like `bsp identify` (the windowed mode's
        estimate, the recursive mode's model checks)."""
        sample = read_joint_state(msg)
        self.identifier.add_raw_angles(sample.t_ns, sample.position, self.now_ns())

    def on_joint_state(self, msg: Any) -> None:
        """Causally filtered joint angles and direction velocities: the weight support, and the recursive mode."""
        sample = read_joint_state(msg)
        if self.settings.support_fraction > 0.0:
            self.publish_support(sample)
        self.identifier.add_joint_state(sample, self.now_ns())

    def on_wrench(self, msg: Any) -> None:
        """One wrench: into world axes (once its frame's rotation at its stamp is known), then identified."""
        sample = read_wrench_stamped(msg)
        now = self.now_ns()
        self.identifier.wrench_received(sample.t_ns, now)
        self._add_wrenches(self.wrench_queue.push(sample.frame_id, sample.t_ns, sample, now))

    def on_emg(self, msg: Any) -> None:
        """EMG envelopes (no header): stamped at their receipt, on the wrench stamps' clock, into the window."""
        channels, values = read_envelope(msg)
        self.identifier.add_emg(channels, values, self.now_ns())

    def _add_wrenches(self, ready: list[tuple[WrenchSample, np.ndarray | None]]) -> None:
        """Wrenches with their rotations (None: waiting for a first transform); the passive moments a mode
        identifies per sample go out at once."""
        for sample, rotation in ready:
            passive = self.identifier.add_wrench(sample, rotation)
            if passive is not None:
                self.passive_pub.publish(build_joint_state(self.types, passive))

    # -- outputs ---------------------------------------------------------------------------------------
    def publish_support(self, sample: JointStateSample) -> None:
        """The wrench the robot should apply to the hand at these angles, only while the estimate is valid."""
        n = self.settings.n_segments
        q = sample.position if sample.position.size == n and np.isfinite(sample.position).all() else None
        fraction = self.settings.support_fraction
        decision = live_support(self.support_estimate, q, self.identifier.lengths, fraction)
        self.support_diagnostics = {f"weight_support.{k}": v for k, v in decision.diagnostics().items()}
        if decision.wrench is None:
            return
        f_y, f_z, m_x = (float(v) for v in decision.wrench.wrench_yzx)
        support = WrenchSample(
            sample.t_ns, self.settings.world_frame, np.array([0.0, f_y, f_z]), np.array([m_x, 0.0, 0.0])
        )
        self.support_pub.publish(build_wrench_stamped(self.types, support))

    def on_update(self) -> None:
        """Compute and publish the estimate (invalid if an input is stale) and the node's health."""
        self.publish(self.identifier.update(self.now_ns()))
        for line in self.frame_notices.new_lines(self.frames):  # each once: a missing or disagreeing rotation
            self.get_logger().warning(line)

    def _outputs(self, estimate: ModeEstimate) -> jobs.EstimateOutputs:
        """An update's estimate serialised for its topics; with a precision target, the signal after it joins the
        estimate (``precision``)."""
        if self.precision is not None:
            self.precision_state = state = self.precision.update(estimate.estimate, self.now_ns())
            estimate = replace(estimate, estimate=estimate.estimate.with_extra({"precision": state.to_json()}))
        return jobs.outputs_from_estimate(estimate)

    def _restart_precision(self) -> None:
        """The estimate restarted: the session's precision signal starts over."""
        if self.precision is not None:
            self.precision.reset()
            self._publish_precision(False)

    def _publish_precision(self, reached: bool) -> None:
        """bsp/precision_reached, latched, whenever it changes."""
        if reached != self.precision_sent:
            self.precision_pub.publish(message_class("std_msgs/msg/Bool")(data=reached))
            self.precision_sent = reached

    def publish(self, outputs: jobs.EstimateOutputs) -> None:
        """Write an estimate's serialised messages, then the node's health on /diagnostics."""
        self.estimate_pub.publish(outputs.cdr["estimate"])
        self.json_pub.publish(outputs.cdr["json"])
        for key, data in outputs.cdr.items():
            if key.startswith("inertia/"):
                self.inertia_pubs[key.removeprefix("inertia/")].publish(data)
        if "passive" in outputs.cdr:
            self.passive_pub.publish(outputs.cdr["passive"])
        self.published += 1
        self.support_estimate = outputs.support
        if self.precision_state is not None:
            self._publish_precision(self.precision_state.reached)
        waiting = any(f.code in WAITING for f in outputs.findings)
        level = OK if outputs.valid else (WARN if waiting else ERROR)
        status = DiagnosticStatusData.with_values(level, NAME, outputs.message, "", self._health())
        diagnostics = DiagnosticArraySample(self.now_ns(), "", (status,))
        self.diag_pub.publish(build_diagnostic_array(self.types, diagnostics))

    def _health(self) -> dict[str, Any]:
        """The /diagnostics values: counters, update times, the wrench frame's source, the weight support, the
        wrench delay."""
        frames = {f"wrench_frame.{f}": source for f, source in self.frames.sources.items()}
        if self.wrench_queue.held:  # wrenches that waited longest for a /tf sample and held the newest one
            frames["wrench_frame.held_without_tf"] = str(self.wrench_queue.held)
        return {
            **self.identifier.counters(),
            "published": self.published,
            **self.identifier.update_times(),
            "wrench_frame_source": self.frame_source.description,
            **frames,
            **self.frame_notices.diagnostics(self.frames),
            **self.support_diagnostics,
            "wrench_delay": self.settings.wrench_delay_note,
            **self._precision_health(),
        }

    def _precision_health(self) -> dict[str, str]:
        """The precision signal on /diagnostics: reached, and the parameter furthest from its target."""
        state = self.precision_state
        if state is None:
            return {}
        out = {"precision.reached": str(state.reached).lower(), "precision.hold_s": f"{state.hold_s:g}"}
        worst = state.worst
        if worst is not None:
            relative = "unknown" if worst.relative_std is None else f"{100 * worst.relative_std:.2f}"
            out["precision.worst"] = f"{worst.owner} {worst.quantity}"
            out["precision.worst_std_percent"] = relative
            out["precision.target_percent"] = f"{100 * worst.target:g}"
        if state.reached_after_s is not None:
            out["precision.reached_after_s"] = f"{state.reached_after_s:.1f}"
        return out


def main(args: list[str] | None = None) -> int:
    """Console entry point (``ros2 run bsp_ros bsp_identifier``); ``args``: a command line like ``sys.argv``."""
    # A callback waiting for the interpreter lock waits up to the switch interval (5 ms by default) while another
    # Python thread holds it; a short interval bounds the recursive mode's wrench -> estimate latency
    # (bench/README.md, live latency).
    sys.setswitchinterval(min(sys.getswitchinterval(), 0.0002))
    return run_node(NAME, BspIdentifierNode, BspIdentifierNode.__doc__ or "", PARAMETERS, args)


if __name__ == "__main__":
    sys.exit(main())
