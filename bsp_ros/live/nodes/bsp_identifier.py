"""`bsp_identifier`: wrench, joint states, wrench frame -> live estimates of segment parameters and passive moments."""

from __future__ import annotations

import sys
import time
import traceback
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np

from bsp_ros.core.contact_point import CONTACT_FROM_ROBOT
from bsp_ros.core.estimate import invalid_document
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.pipeline import IdentifyOptions
from bsp_ros.core.sensor_zero import ZERO_SD_N, ZERO_SD_NM
from bsp_ros.core.streams import segments_for
from bsp_ros.core.tare import Tare, read_tare_file
from bsp_ros.core.weight_support import live_support
from bsp_ros.errors import BspError, InputError
from bsp_ros.live.nodes import estimate_jobs as jobs
from bsp_ros.live.online.frames import WrenchFrames, WrenchQueue, frame_source, rotation_from_quaternion_xyzw
from bsp_ros.live.online.recursive_check import WindowCheck
from bsp_ros.live.online.recursive_feed import RecursiveFeed
from bsp_ros.live.online.windowed import (
    WindowConfig,
    WindowedIdentifier,
    WindowEstimate,
)
from bsp_ros.live.online.wrench_input import WrenchInput
from bsp_ros.live.runtime.parameters import Param, declare_parameters
from bsp_ros.live.runtime.qos import rclpy_qos
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
from msg_adapters.joint_state import JointStateSample, build_joint_state, read_joint_state
from msg_adapters.tf import read_tf_message, read_transform_stamped
from msg_adapters.wrench import WrenchSample, build_wrench_stamped, read_wrench_stamped

NAME = "bsp_identifier"
MODES = ("windowed", "recursive")
TF_TYPE = "tf2_msgs/msg/TFMessage"

PARAMETERS = (
    Param("mode", "windowed", "windowed (sliding window) or recursive (per sample)", choices=MODES),
    Param("n_segments", 3, "2 (mechanical arm) or 3 (human arm)", lo=2, hi=3),
    Param("window_s", 30.0, "sliding window length", "s", lo=1.0, hi=3600.0),
    Param("update_hz", 5.0, "estimate rate", "Hz", lo=0.1, hi=100.0),
    Param("stale_s", 0.4, "an input silent this long makes the estimate invalid", "s", lo=0.01, hi=60.0),
    Param(
        "method", "joint", "joint (ours) or paper (the method paper's sequential procedure)", choices=("joint", "paper")
    ),
    Param("passive", "coulomb", "passive model, e.g. coulomb+viscous"),
    Param("body_mass_kg", 0.0, "subject body mass for the prior (0: unknown)", "kg", lo=0.0, hi=300.0),
    Param("height_m", 0.0, "subject height (0: unknown)", "m", lo=0.0, hi=2.5),
    Param("sex", "male", "anthropometric table", choices=("male", "female")),
    Param("world_frame", "world", "frame of the markers and of gravity (z up)"),
    Param("wrench_topic", "/ft_sensor/wrench", "WrenchStamped topic"),
    Param(
        "wrench_frame_source",
        "auto",
        "where the wrench frame's rotation comes from: tf (/tf_static and /tf), topic (TransformStamped of the "
        "wrench frame in world on wrench_frame_topic, e.g. the robot's flange: a sensor that turns without tf2_msgs), "
        "parameter (wrench_frame_rotation_xyzw), or auto (tf if tf2_msgs is installed, else the parameter)",
        choices=("auto", "tf", "topic", "parameter"),
    ),
    Param(
        "wrench_frame_topic",
        "ft_sensor/transform",
        "geometry_msgs/TransformStamped topic of the wrench frame in world (wrench_frame_source topic)",
    ),
    Param(
        "wrench_frame_rotation_xyzw",
        [0.0, 0.0, 0.0, 1.0],
        "rotation world <- wrench frame as a unit quaternion [x, y, z, w], used without tf",
    ),
    Param(
        "tare_file",
        "",
        "a `bsp tare` file (bsp_ros/core/tare/1) of this sensor: its offset and handle load are removed from every "
        "wrench and its uncertainty joins the windowed estimate's ('': none, and the estimate says so)",
    ),
    Param(
        "zero_sd_n",
        ZERO_SD_N,
        "without a tare, how far (1 sd per sensor axis) the sensor's force zero may be off: the data cannot tell a "
        "force offset from arm weight, so it is in the std (`bsp identify --zero-sd-n`)",
        "N",
        lo=0.0,
        hi=100.0,
    ),
    Param("zero_sd_nm", ZERO_SD_NM, "the same for the sensor's moment zero", "N m", lo=0.0, hi=10.0),
    Param(
        "support_fraction",
        0.0,
        "share of the identified arm's gravity torques the robot should carry (bsp/weight_support, published "
        "at the joint-state rate while the estimate is valid; 0: not published)",
        lo=0.0,
        hi=1.0,
    ),
    Param(
        "wrench_delay_s",
        0.0,
        "delay of the wrench stamps behind the joint-state (marker) stamps the cell knows: a wrench stamped t was "
        "measured at t - wrench_delay_s; its stamps are shifted back by it (`bsp identify --wrench-delay-s`)",
        "s",
        lo=-10.0,
        hi=10.0,
    ),
    Param(
        "tf_wait_s",
        2.0,
        "wait this long for the wrench frame's transform before taking it as world",
        "s",
        lo=0.0,
        hi=60.0,
    ),
)


# Invalid estimates that wait for a session to start (a warning on /diagnostics, not an error).
WAITING = frozenset({FindingCode.INPUT_WAITING, FindingCode.WAITING_FOR_CHECK})


class BspIdentifierNode(RosNode):
    """Identifies online, in a sliding window (default) or recursively, and publishes the estimates.

    An estimate is published invalid (level ERROR) when an input is stale (nothing received for
    ``stale_s`` of wall time), and samples that are non-finite, out of order or duplicated never enter it.
    The callbacks adapt messages and hand them to the online blocks (``bsp_ros.live.online``).
    """

    def __init__(self) -> None:
        super().__init__(NAME)
        p = declare_parameters(self, PARAMETERS)
        self.mode = p["mode"]
        self.n = p["n_segments"]
        self.stale_s = p["stale_s"]
        self.world_frame = p["world_frame"]
        try:
            parameter_rotation = rotation_from_quaternion_xyzw(p["wrench_frame_rotation_xyzw"])
        except ValueError as exc:
            raise InputError(f"{NAME}: parameter wrench_frame_rotation_xyzw: {exc}") from exc
        try:
            self.frame_source = frame_source(p["wrench_frame_source"], has_message(TF_TYPE), p["wrench_frame_topic"])
        except ValueError as exc:
            raise InputError(f"{NAME}: {exc}") from exc
        self.frames = WrenchFrames(self.world_frame, self.frame_source.transforms, parameter_rotation, p["tf_wait_s"])
        self.wrench_queue = WrenchQueue(self.frames)  # a turning sensor's wrench waits for the /tf after it
        self.get_logger().info(
            f"wrench frame rotation from {self.frame_source.description}"
            + ("" if self.frame_source.transforms else f" = {p['wrench_frame_rotation_xyzw']} ({TF_TYPE} not used)")
        )
        subject = SubjectInfo(p["body_mass_kg"] or None, p["height_m"] or None, p["sex"])
        try:
            passive = PassiveModel.parse(p["passive"])
        except (BspError, ValueError) as exc:
            raise InputError(f"{NAME}: parameter passive: {exc}") from exc
        self.tare: Tare | None = None
        if p["tare_file"]:
            try:
                self.tare = read_tare_file(p["tare_file"])
            except BspError as exc:
                raise InputError(f"{NAME}: parameter tare_file {p['tare_file']}: {exc}") from exc
            self.get_logger().info(f"tare {p['tare_file']} of frame {self.tare.frame_id!r} applied to every wrench")
        self.wrench_rotation: tuple[str, np.ndarray] | None = None  # the latest wrench's frame and rotation
        self.wrench_input = WrenchInput(self.tare, round(p["wrench_delay_s"] * 1e9))
        # The model named by the parameter, kept: a window showing an elastic moment it lacks is invalid with the
        # warning (choosing among the elastic family per 5 Hz update is `bsp identify --passive auto`'s work).
        self.options = IdentifyOptions(
            method=p["method"],
            passive=passive,
            subject=subject,
            tare=self.tare,
            wrench_delay_s=p["wrench_delay_s"],
            elastic_fallback=False,
            zero_sd_n=p["zero_sd_n"],
            zero_sd_nm=p["zero_sd_nm"],
        )
        # Its buffers take the callbacks' samples; its estimator (the model checks' schedule) runs in the timer's.
        # The recursive mode identifies its window every recursive_check.CHECK_EVERY updates, each time with every
        # model check (its std and verdict join the filter's estimate).
        check_every = 1 if self.mode == "recursive" else WindowConfig.elastic_check_every
        self.windowed = WindowedIdentifier(
            self.n, WindowConfig(p["window_s"], 60.0, self.options, elastic_check_every=check_every)
        )
        self.window_check = WindowCheck(self.windowed)
        self.recursive = RecursiveFeed(self.n, self.options.passive, subject)
        self.lengths: np.ndarray | None = None
        # Unfiltered angles that came before the first segment lengths (a topic of their own, which can match
        # later or be taken after them); they join the window when the lengths arrive.
        self.early_angles: deque[tuple[int, np.ndarray]] = deque(maxlen=4000)
        self.last_receive: dict[str, int | None] = {"wrench": None, "joint_states": None}
        self.counts = {"wrench": 0, "joint_states": 0, "refused": 0}
        self.published = 0
        # Every estimate is computed in the timer's callback, on the executor thread: a windowed update refits the
        # model its last check chose (~8 ms for 30 s at 1 kHz, the checks every elastic_check_every updates ~25
        # ms: bench/live_window_update.py), while the wrenches wait in their subscription's queue (1 s deep) and
        # are taken right after it. A worker thread kept the callbacks going, but the two traded the interpreter
        # lock every 0.2 ms and the update took longer in the node (bench/README.md, live latency).
        self.support_fraction = float(p["support_fraction"])
        self.support_estimate: dict[str, Any] | None = None  # set with each estimate
        self.support_diagnostics: dict[str, str] = {}
        # The last ~10 s of updates: compute time and the thread's own CPU time in it, s. Below the compute time,
        # an update waited for a core (the other nodes, Fast DDS's threads).
        self.update_s: deque[tuple[float, float]] = deque(maxlen=int(10 * p["update_hz"]) + 1)
        self.types = message_class
        estimates = rclpy_qos("estimates")
        self.estimate_pub = self.create_publisher(
            message_class("diagnostic_msgs/msg/DiagnosticArray"), "bsp/estimate", estimates
        )
        self.json_pub = self.create_publisher(message_class("std_msgs/msg/String"), "bsp/estimate_json", estimates)
        joint_state = message_class("sensor_msgs/msg/JointState")
        self.passive_pub = self.create_publisher(joint_state, "bsp/passive_moments", estimates)
        self.inertia_pubs = {
            s: self.create_publisher(message_class("geometry_msgs/msg/InertiaStamped"), f"bsp/{s}/inertia", estimates)
            for s in segments_for(self.n)
        }
        self.support_pub = self.create_publisher(
            message_class("geometry_msgs/msg/WrenchStamped"), "bsp/weight_support", rclpy_qos("default")
        )
        self.diag_pub = self.create_publisher(
            message_class("diagnostic_msgs/msg/DiagnosticArray"), "/diagnostics", rclpy_qos("default")
        )
        wrench = message_class("geometry_msgs/msg/WrenchStamped")
        self.create_subscription(wrench, p["wrench_topic"], self.on_wrench, rclpy_qos("sensor_input"))
        # The causal joint states only where they are used (each message costs the executor thread its
        # deserialisation); the unfiltered angles always: they fill the window, the windowed mode's estimate and the
        # recursive mode's model checks.
        states = rclpy_qos("state_input")
        if self.mode == "recursive" or self.support_fraction > 0.0:
            self.create_subscription(joint_state, "arm/joint_states", self.on_joint_state, states)
        self.create_subscription(joint_state, "arm/joint_angles_raw", self.on_raw_angles, states)
        self.create_subscription(joint_state, "arm/segment_lengths", self.on_lengths, estimates)
        self.create_subscription(
            message_class("std_msgs/msg/String"), "arm/contact_point", self.on_contact_point, rclpy_qos("tf_static")
        )
        if self.frame_source.tf:
            tf = message_class(TF_TYPE)
            self.create_subscription(tf, "/tf_static", self.on_tf_static, rclpy_qos("tf_static_listener"))
            self.create_subscription(tf, "/tf", self.on_tf, rclpy_qos("tf"))
        if self.frame_source.topic:
            transform = message_class("geometry_msgs/msg/TransformStamped")
            self.create_subscription(transform, p["wrench_frame_topic"], self.on_transform, rclpy_qos("tf"))
        self.create_timer(1.0 / p["update_hz"], self.on_update)

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
        for sample, rotation in self.wrench_queue.release(self.now_ns()):
            self._add_wrench(sample, rotation)

    def on_transform(self, msg: Any) -> None:
        """One stamped transform of the wrench frame (``wrench_frame_source`` topic), handled as a /tf sample."""
        self._restart_on(self.frames.on_transforms([read_transform_stamped(msg)]))
        for sample, rotation in self.wrench_queue.release(self.now_ns()):
            self._add_wrench(sample, rotation)

    def _restart_on(self, changed: list[str]) -> None:
        """A fixed wrench rotation that changed restarts the estimate."""
        for frame_id in changed:
            # Samples already buffered were rotated the old way: they must not mix with new ones.
            self.get_logger().warning(f"transform of {frame_id} changed: estimate restarted")
            self.windowed.reset()
            self.recursive.reset()

    def on_contact_point(self, msg: Any) -> None:
        """Where the angles' contact point comes from (`joint_angle_estimator`): the robot's handle pose holds
        the robot's registration sd in the estimate, a skin marker the marker placement sd."""
        robot = msg.data == CONTACT_FROM_ROBOT
        if robot != self.windowed.contact_from_robot:
            # The hand's segment length changes with the source: samples of both must not mix.
            self.get_logger().info(f"contact point: {msg.data}; estimate restarted")
            self.windowed.reset()
            self.recursive.reset()
            self.windowed.contact_from_robot = robot

    def on_lengths(self, msg: Any) -> None:
        """Segment lengths from the joint angle estimator."""
        sample = read_joint_state(msg)
        if sample.position.size == self.n and np.isfinite(sample.position).all() and (sample.position > 0).all():
            self.lengths = sample.position
            while self.early_angles:
                self.add_raw_angles(*self.early_angles.popleft())

    def on_raw_angles(self, msg: Any) -> None:
        """Unfiltered joint angles: the window filters them with zero phase, like `bsp identify` (the windowed mode's
        estimate, the recursive mode's model checks)."""
        sample = read_joint_state(msg)
        self.last_receive["joint_states"] = self.now_ns()
        if sample.position.size != self.n:
            return
        if self.lengths is None:
            self.early_angles.append((sample.t_ns, sample.position))
            return
        self.add_raw_angles(sample.t_ns, sample.position)

    def add_raw_angles(self, t_ns: int, q_rad: np.ndarray) -> None:
        """Unfiltered angles into the window, with the newest segment lengths."""
        assert self.lengths is not None
        accepted = self.windowed.add_joint_state(t_ns, q_rad, self.lengths)
        # The recursive mode counts its joint states on arm/joint_states; these only fill its checks' window.
        key = ("joint_states" if self.mode == "windowed" else "raw_angles") if accepted else "refused"
        self.counts[key] = self.counts.get(key, 0) + 1

    def on_joint_state(self, msg: Any) -> None:
        """Causally filtered joint angles and direction velocities: the weight support, and the recursive mode."""
        sample = read_joint_state(msg)
        if self.support_fraction > 0.0:
            self.publish_support(sample)
        if self.mode != "recursive":
            return
        self.last_receive["joint_states"] = self.now_ns()
        accepted = self.recursive.add_joint_state(sample.t_ns, sample.position, sample.velocity, self.lengths)
        self.counts["joint_states" if accepted else "refused"] += 1

    def on_wrench(self, msg: Any) -> None:
        """One wrench: into world axes, then into the window or the recursive filter."""
        sample = read_wrench_stamped(msg)
        self.last_receive["wrench"] = self.now_ns()
        for ready, rotation in self.wrench_queue.push(sample.frame_id, sample.t_ns, sample, self.now_ns()):
            self._add_wrench(ready, rotation)

    def _add_wrench(self, sample: WrenchSample, rotation: np.ndarray | None) -> None:
        """A wrench with its rotation at its stamp (None: waiting for a first transform)."""
        if rotation is None:
            self.counts["waiting_for_tf"] = self.counts.get("waiting_for_tf", 0) + 1
            return
        world = self.wrench_input.world(sample, rotation)
        if world is None:
            self.counts["tare_frame_mismatch"] = self.counts.get("tare_frame_mismatch", 0) + 1
            return
        self.wrench_rotation = (sample.frame_id, rotation)
        t_ns, wrench_yzx = world
        if self.mode == "windowed":
            accepted = self.windowed.add_wrench(t_ns, wrench_yzx)
        else:
            accepted, coulomb_nm = self.recursive.add_wrench(t_ns, wrench_yzx, self.lengths)
            joints = self.recursive.passive_joints
            if coulomb_nm is not None and len(joints) == coulomb_nm.size:
                passive = JointStateSample(sample.t_ns, "", joints, np.zeros(0), np.zeros(0), coulomb_nm)
                self.passive_pub.publish(build_joint_state(self.types, passive))
            self.windowed.add_wrench(t_ns, wrench_yzx)  # after the passive moments went out: for the checks
        self.counts["wrench" if accepted else "refused"] += 1

    # -- outputs ---------------------------------------------------------------------------------------
    def publish_support(self, sample: JointStateSample) -> None:
        """The wrench the robot should apply to the hand at these angles, only while the estimate is valid."""
        q = sample.position if sample.position.size == self.n and np.isfinite(sample.position).all() else None
        decision = live_support(self.support_estimate, q, self.lengths, self.support_fraction)
        self.support_diagnostics = {f"weight_support.{k}": v for k, v in decision.diagnostics().items()}
        if decision.wrench is None:
            return
        f_y, f_z, m_x = (float(v) for v in decision.wrench.wrench_yzx)
        support = WrenchSample(sample.t_ns, self.world_frame, np.array([0.0, f_y, f_z]), np.array([m_x, 0.0, 0.0]))
        self.support_pub.publish(build_wrench_stamped(self.types, support))

    def stale_reason(self) -> Finding | None:
        """Why no estimate can be made now (an input never came or fell silent for ``stale_s``), or None."""
        now = self.now_ns()
        for name, last in self.last_receive.items():
            if last is None:
                return Finding(code=FindingCode.INPUT_WAITING, values={"what": name})
            if now - last > self.stale_s * 1e9:
                return Finding(code=FindingCode.INPUT_STALE, values={"what": name, "silent_s": (now - last) / 1e9})
        if self.lengths is None:
            return Finding(code=FindingCode.INPUT_WAITING, values={"what": "segment lengths"})
        return None

    def on_update(self) -> None:
        """Compute and publish the estimate (invalid if an input is stale) and the node's health."""
        reason = self.stale_reason()
        counts = dict(self.counts)
        if self.mode == "windowed":
            self._update_windowed(reason, counts)
        else:
            counts["wrench_spikes"] = self.recursive.spike_gate.spikes  # taken, kept out of the filter
            self._update_recursive(reason, counts)

    def _update_windowed(self, reason: Finding | None, counts: dict[str, int]) -> None:
        """The newest window's estimate, published as soon as it is computed (stamped with the window's newest
        wrench); a quick verdict (stale, waiting) goes out instead when there is no window to identify."""
        # The sensor's orientation rides with the window: the zero's uncertainty (the tare's, or zero_sd_n's without
        # one) joins the std, as `bsp identify` adds it.
        window = self.windowed.snapshot(orientation=self.wrench_rotation) if reason is None else None
        if window is None or isinstance(window, WindowEstimate):
            if window is None:
                assert reason is not None  # a snapshot is taken only without one
                document, stamp = invalid_document(self.options.method, reason), self.now_ns()
            else:
                document, stamp = window.document, window.last_wrench_t_ns or self.now_ns()
            document["mode"] = self.mode
            self.publish(jobs.outputs_from_document(document, stamp, with_passive=True), counts)
            return
        self.publish(self._timed(lambda: jobs.window_estimate(self.windowed.estimator, window)), counts)

    def _update_recursive(self, reason: Finding | None, counts: dict[str, int]) -> None:
        """The filter's state, held to its window's checked estimate, fused with the prior and published (~2 ms;
        every 10 s the window's model checks, 20-40 ms)."""
        job: Callable[[], jobs.EstimateOutputs]
        if reason is not None:
            document, now = invalid_document(self.options.method, reason), self.now_ns()
            document["mode"] = self.mode
            job = lambda: jobs.outputs_from_document(document, now, with_passive=False)  # noqa: E731 - in order
        else:
            assert self.lengths is not None  # stale_reason() waits for them
            lengths, stamp = self.lengths.copy(), self.recursive.guard.last_t_ns or 0
            robot = self.windowed.contact_from_robot

            def job() -> jobs.EstimateOutputs:
                self.window_check.tick(self.wrench_rotation)  # the window's model checks, when due (timed with it)
                result = self.window_check.checked(self.recursive.identifier.result())
                return jobs.recursive_estimate(result, lengths, self.options, stamp, robot)

        self.publish(self._timed(job), counts)

    def _timed(self, job: Callable[[], jobs.EstimateOutputs]) -> jobs.EstimateOutputs:
        """Run an estimate job and record how long it took; a job that fails
        unexpectedly gives an invalid estimate (published, not lost) and a logged traceback."""
        started, started_cpu = time.perf_counter(), time.thread_time()
        try:
            outputs = job()
        except Exception as exc:
            self.get_logger().error(f"estimate failed: {traceback.format_exc()}")
            document = jobs.internal_error_document(self.options.method, exc)
            document["mode"] = self.mode
            outputs = jobs.outputs_from_document(document, self.now_ns(), with_passive=False)
        self.update_s.append((time.perf_counter() - started, time.thread_time() - started_cpu))
        return outputs

    def publish(self, outputs: jobs.EstimateOutputs, counts: dict[str, int]) -> None:
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
        waiting = any(f.code in WAITING for f in outputs.findings)
        level = OK if outputs.valid else (WARN if waiting else ERROR)
        timing = {}
        if self.update_s:  # how long an update takes: near the period, the node cannot keep up
            wall_cpu_ms = 1e3 * np.array(self.update_s)
            mean, top = wall_cpu_ms.mean(axis=0), wall_cpu_ms.max(axis=0)
            timing = {
                "update_ms_mean": f"{mean[0]:.1f}",
                "update_ms_max": f"{top[0]:.1f}",
                "update_cpu_ms_mean": f"{mean[1]:.1f}",
                "update_cpu_ms_max": f"{top[1]:.1f}",
            }
        frames = {f"wrench_frame.{f}": source for f, source in self.frames.sources.items()}
        if self.wrench_queue.held:  # wrenches that waited longest for a /tf sample and held the newest one
            frames["wrench_frame.held_without_tf"] = str(self.wrench_queue.held)
        values = {
            **counts,
            "published": self.published,
            **timing,
            "wrench_frame_source": self.frame_source.description,
            **frames,
            **self.support_diagnostics,
        }
        status = DiagnosticStatusData.with_values(level, NAME, outputs.message, "", values)
        diagnostics = DiagnosticArraySample(self.now_ns(), "", (status,))
        self.diag_pub.publish(build_diagnostic_array(self.types, diagnostics))


def main(args: list[str] | None = None) -> int:
    """Console entry point (``ros2 run bsp_ros bsp_identifier``); ``args``: a command line like ``sys.argv``."""
    # A callback waiting for the interpreter lock waits up to the switch interval (5 ms by default) while another
    # Python thread holds it; 0.2 ms keeps the recursive mode's latency lower (bench/README.md, live latency).
    sys.setswitchinterval(min(sys.getswitchinterval(), 0.0002))
    return run_node(NAME, BspIdentifierNode, BspIdentifierNode.__doc__ or "", PARAMETERS, args)


if __name__ == "__main__":
    sys.exit(main())
