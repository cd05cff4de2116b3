"""`bsp_identifier`: wrench + joint states + tf -> live estimates of segment parameters and passive moments."""

from __future__ import annotations

import sys
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np

from bsp_ros.estimate import invalid_document
from bsp_ros.fusion import SubjectInfo
from bsp_ros.identification.passive import PassiveModel
from bsp_ros.identification.recursive import RecursiveConfig, RecursiveIdentifier
from bsp_ros.model import contact_torques_one_nm
from bsp_ros.nodes import estimate_jobs as jobs
from bsp_ros.online.guard import StreamGuard
from bsp_ros.online.windowed import WindowConfig, WindowedIdentifier, WindowEstimate, WindowSamples
from bsp_ros.pipeline import IdentifyOptions
from bsp_ros.runtime import run_node
from bsp_ros.runtime.offload import ProcessOffload
from bsp_ros.runtime.worker import LatestJobWorker
from bsp_ros.streams import segments_for
from msg_adapters.diagnostics import (
    ERROR,
    OK,
    WARN,
    DiagnosticArraySample,
    DiagnosticStatusData,
    build_diagnostic_array,
)
from msg_adapters.joint_state import JointStateSample, build_joint_state, read_joint_state
from msg_adapters.tf import read_tf_message, rotation_between
from msg_adapters.wrench import read_wrench_stamped

NAME = "bsp_identifier"
MODES = ("windowed", "recursive")


class BspIdentifierNode:
    """Identifies online, in a sliding window (default) or recursively, and publishes the estimates.

    An estimate is published invalid (level ERROR) when an input is stale (nothing received for
    ``stale_s`` of wall time), and samples that are non-finite, out of order or duplicated never enter it.
    """

    def __init__(self, node: Any) -> None:
        self.node = node
        p = node.declare_parameter
        self.mode = p("mode", "windowed", "windowed (sliding window) or recursive (per sample)")
        if self.mode not in MODES:
            from bsp_ros.errors import InputError

            raise InputError(f"{NAME}: parameter mode must be one of {MODES}, got {self.mode!r}")
        self.n = p("n_segments", 3, "2 (mechanical arm) or 3 (human arm)", lo=2, hi=3)
        window_s = p("window_s", 30.0, "sliding window length", "s", lo=1.0, hi=3600.0)
        update_hz = p("update_hz", 5.0, "estimate rate", "Hz", lo=0.1, hi=100.0)
        self.stale_s = p("stale_s", 0.4, "an input silent this long makes the estimate invalid", "s", lo=0.01, hi=60.0)
        method = p("method", "joint", "joint (ours) or paper (the method paper's sequential procedure)")
        passive = p("passive", "coulomb", "passive model, e.g. coulomb+viscous")
        body_mass = p("body_mass_kg", 0.0, "subject body mass for the prior (0: unknown)", "kg", lo=0.0, hi=300.0)
        height = p("height_m", 0.0, "subject height (0: unknown)", "m", lo=0.0, hi=2.5)
        sex = p("sex", "male", "anthropometric table: male or female")
        self.world_frame = p("world_frame", "world", "frame of the markers and of gravity (z up)")
        self.wrench_topic = p("wrench_topic", "/ft_sensor/wrench", "WrenchStamped topic")
        self.tf_wait_s = p(
            "tf_wait_s",
            2.0,
            "wait this long for the wrench frame's transform before taking it as world",
            "s",
            lo=0.0,
            hi=60.0,
        )
        self.first_wrench_wall_ns: int | None = None
        subject = SubjectInfo(body_mass or None, height or None, sex)
        self.options = IdentifyOptions(method=method, passive=PassiveModel.parse(passive), subject=subject)
        self.windowed = WindowedIdentifier(self.n, WindowConfig(window_s, 60.0, self.options))
        self.recursive = RecursiveIdentifier(self.n, RecursiveConfig(passive=self.options.passive))
        self.recursive_guard = StreamGuard("wrench")
        self.transforms: dict[str, Any] = {}
        self.rotations: dict[str, np.ndarray] = {}
        self.assumed_world: set[str] = set()
        self.lengths: np.ndarray | None = None
        self.passive_joints: tuple[str, ...] | None = None
        self.joint_states: list[tuple[int, np.ndarray, np.ndarray]] = []
        self.last_receive = {"wrench": None, "joint_states": None}
        self.counts = {"wrench": 0, "joint_states": 0, "refused": 0}
        self.published = 0
        self.worker = LatestJobWorker(f"{NAME}-estimate")
        # The estimates run in a child process (see ProcessOffload); a worker thread waits for them.
        # In recursive mode the per-sample filter here comes first and the child only fuses at 5 Hz: it runs
        # in the background. A windowed estimate is the main work and keeps a normal priority.
        background = self.mode == "recursive"
        self.offload = ProcessOffload(jobs.init_worker, (self.n, self.windowed.config, background))
        self.generation = 0  # windowed: bumped by a verdict that supersedes estimates still computing
        self.ready: tuple[int, jobs.EstimateOutputs] | None = None
        self.offload.run(jobs.ping)
        self.update_s: deque[float] = deque(maxlen=int(10 * update_hz) + 1)  # compute time of the last ~10 s
        self.types = node.message_class
        self.estimate_pub = node.create_publisher("diagnostic_msgs/msg/DiagnosticArray", "bsp/estimate", "estimates")
        self.json_pub = node.create_publisher("std_msgs/msg/String", "bsp/estimate_json", "estimates")
        self.passive_pub = node.create_publisher("sensor_msgs/msg/JointState", "bsp/passive_moments", "estimates")
        self.inertia_pubs = {
            s: node.create_publisher("geometry_msgs/msg/InertiaStamped", f"bsp/{s}/inertia", "estimates")
            for s in segments_for(self.n)
        }
        self.diag_pub = node.create_publisher("diagnostic_msgs/msg/DiagnosticArray", "/diagnostics", "default")
        node.create_subscription("geometry_msgs/msg/WrenchStamped", self.wrench_topic, self.on_wrench, "sensor_data")
        node.create_subscription("sensor_msgs/msg/JointState", "arm/joint_states", self.on_joint_state, "estimates")
        node.create_subscription("sensor_msgs/msg/JointState", "arm/joint_angles_raw", self.on_raw_angles, "estimates")
        node.create_subscription("sensor_msgs/msg/JointState", "arm/segment_lengths", self.on_lengths, "estimates")
        node.create_subscription("tf2_msgs/msg/TFMessage", "/tf_static", self.on_tf, "tf_static_listener")
        node.create_subscription("tf2_msgs/msg/TFMessage", "/tf", self.on_tf, "tf")
        node.create_timer(1.0 / update_hz, self.on_update)

    # -- inputs ---------------------------------------------------------------------------------------
    def on_tf(self, msg: Any) -> None:
        """Keep the newest transform of every child frame; a changed wrench rotation restarts the estimate."""
        for transform in read_tf_message(msg):
            self.transforms[transform.child_frame] = transform
        for frame_id, old in list(self.rotations.items()):
            new = rotation_between(self.transforms.values(), self.world_frame, frame_id)
            if new is not None and not np.allclose(new, old, atol=1e-9):
                # Samples already buffered were rotated the old way: they must not mix with new ones.
                self.node.get_logger().warning("transform of %s changed: estimate restarted", frame_id)
                self.windowed.reset()
                self.recursive.reset()
                self.rotations[frame_id] = new

    def rotation_for(self, frame_id: str) -> np.ndarray | None:
        """Rotation from ``frame_id`` to the world frame.

        None while waiting up to ``tf_wait_s`` for a transform; after that, identity with a warning
        (CONTRACT.md: no transform means the wrench frame is ``world``).
        """
        if frame_id in self.rotations:
            return self.rotations[frame_id]
        rotation = (
            np.eye(3)
            if frame_id == self.world_frame
            else rotation_between(self.transforms.values(), self.world_frame, frame_id)
        )
        if rotation is None:
            now = self.node.now_ns()
            self.first_wrench_wall_ns = self.first_wrench_wall_ns or now
            if now - self.first_wrench_wall_ns < self.tf_wait_s * 1e9:
                return None
            rotation = np.eye(3)
            self.node.get_logger().warning("no transform %s -> %s: taken as world", frame_id, self.world_frame)
        self.rotations[frame_id] = rotation
        return rotation

    def on_lengths(self, msg: Any) -> None:
        """Segment lengths from the joint angle estimator."""
        sample = read_joint_state(msg)
        if sample.position.size == self.n and np.isfinite(sample.position).all() and (sample.position > 0).all():
            self.lengths = sample.position

    def on_raw_angles(self, msg: Any) -> None:
        """Unfiltered joint angles: the windowed mode filters them with zero phase, like `bsp identify`."""
        sample = read_joint_state(msg)
        if self.mode != "windowed":
            return
        self.last_receive["joint_states"] = self.node.now_ns()
        if self.lengths is None or sample.position.size != self.n:
            return
        accepted = self.windowed.add_joint_state(sample.t_ns, sample.position, self.lengths)
        self.counts["joint_states" if accepted else "refused"] += 1

    def on_joint_state(self, msg: Any) -> None:
        """Causally filtered joint angles and direction velocities (the recursive mode)."""
        sample = read_joint_state(msg)
        if self.mode != "recursive":
            return
        self.last_receive["joint_states"] = self.node.now_ns()
        if sample.position.size != self.n or not np.isfinite(sample.position).all():
            self.counts["refused"] += 1
            return
        velocity = sample.velocity if sample.velocity.size == self.n else np.zeros(self.n)
        if self.joint_states and sample.t_ns <= self.joint_states[-1][0]:
            if self.joint_states[-1][0] - sample.t_ns <= 1e9:  # out of order or duplicate; a jump restarts
                self.counts["refused"] += 1
                return
            self.joint_states = []
        self.counts["joint_states"] += 1
        self.joint_states = [*self.joint_states[-1:], (sample.t_ns, sample.position, velocity)]

    def on_wrench(self, msg: Any) -> None:
        """One wrench: into world axes, then into the window or the recursive filter."""
        sample = read_wrench_stamped(msg)
        self.last_receive["wrench"] = self.node.now_ns()
        rotation = self.rotation_for(sample.frame_id)
        if rotation is None:
            self.counts["waiting_for_tf"] = self.counts.get("waiting_for_tf", 0) + 1
            return
        force, torque = rotation @ sample.force_n, rotation @ sample.torque_nm
        wrench_yzx = np.array([force[1], force[2], torque[0]])
        if self.mode == "windowed":
            accepted = self.windowed.add_wrench(sample.t_ns, wrench_yzx)
        else:
            accepted = self.update_recursive(sample.t_ns, wrench_yzx)
        self.counts["wrench" if accepted else "refused"] += 1

    def update_recursive(self, t_ns: int, wrench_yzx: np.ndarray) -> bool:
        verdict = self.recursive_guard.check(t_ns, wrench_yzx)
        if verdict in ("jump", "gap"):
            self.recursive.reset()
        if verdict == "refused" or self.lengths is None or not self.joint_states:
            return verdict != "refused"
        (t0, q0, v0), (t1, q1, v1) = self.joint_states[0], self.joint_states[-1]
        if t_ns - t1 > 0.1e9 or t_ns < t0 - 0.1e9:  # no angle near this wrench
            return True
        w = 0.0 if t1 == t0 else min(max((t_ns - t0) / (t1 - t0), 0.0), 1.0)
        q, v = (1 - w) * q0 + w * q1, (1 - w) * v0 + w * v1
        tau = contact_torques_one_nm(q, self.lengths, wrench_yzx)
        if self.recursive.update(t_ns, q, v, tau):
            passive = self.recursive.theta[self.n :: len(self.options.passive.terms)]
            if self.passive_joints is None:
                self.passive_joints = tuple(name for key, name in self.recursive.names if key == "coulomb_nm")
            if len(self.passive_joints) == len(passive):
                sample = JointStateSample(t_ns, "", self.passive_joints, np.zeros(0), np.zeros(0), passive)
                self.passive_pub.publish(build_joint_state(self.types, sample))
        return True

    # -- outputs --------------------------------------------------------------------------------------
    def stale_reason(self) -> str | None:
        now = self.node.now_ns()
        for name, last in self.last_receive.items():
            if last is None:
                return f"waiting for {name}"
            if now - last > self.stale_s * 1e9:
                return f"stale input: no {name} for {(now - last) / 1e9:.2f} s"
        if self.lengths is None:
            return "waiting for segment lengths"
        return None

    def on_update(self) -> None:
        """Publish the estimate (invalid if an input is stale) and the node's health.

        The slow part runs in a worker process, waited for by a worker thread, so that the wrench callbacks
        never wait for an estimate; here, on the executor thread, only what it needs is copied.
        """
        reason = self.stale_reason()
        counts = dict(self.counts)
        if self.mode == "windowed":
            self._update_windowed(reason, counts)
        else:
            self._update_recursive(reason, counts)

    def _update_windowed(self, reason: str | None, counts: dict[str, int]) -> None:
        """Publish on the timer grid: the estimate computed since the last tick (of that tick's window), then
        start the next one. Consumers get an update every period, one period after the window it describes
        (its stamp says which). A quick verdict (stale, waiting) goes out at once and supersedes any estimate
        still computing."""
        window = self.windowed.snapshot() if reason is None else None
        if window is None or isinstance(window, WindowEstimate):
            self.generation += 1
            if window is None:
                document, stamp = invalid_document(self.options.method, str(reason)), self.node.now_ns()
            else:
                document, stamp = window.document, window.last_wrench_t_ns or self.node.now_ns()
            document["mode"] = self.mode
            self.publish(jobs.outputs_from_document(document, stamp, with_passive=True), counts)
            return
        ready, self.ready = self.ready, None
        if ready is not None and ready[0] == self.generation:
            self.publish(ready[1], counts)
        generation = self.generation
        self.worker.submit(lambda: self._compute_window(window, generation))

    def _compute_window(self, window: WindowSamples, generation: int) -> None:
        """On the worker thread: identify a window in the worker process; keep it for the next tick."""
        self.ready = (generation, self._timed(lambda: self.offload.run(jobs.window_estimate, window)))

    def _update_recursive(self, reason: str | None, counts: dict[str, int]) -> None:
        """The filter's state is copied here; the worker fuses it with the prior and publishes it at once."""
        job: Callable[[], jobs.EstimateOutputs]
        if reason is not None:
            document, now = invalid_document(self.options.method, reason), self.node.now_ns()
            document["mode"] = self.mode
            job = lambda: jobs.outputs_from_document(document, now, with_passive=False)  # noqa: E731 - in order
        else:
            assert self.lengths is not None  # stale_reason() waits for them
            result, lengths, stamp = self.recursive.result(), self.lengths.copy(), self.recursive_guard.last_t_ns or 0
            job = lambda: self.offload.run(jobs.recursive_estimate, result, lengths, self.options, stamp)  # noqa: E731
        self.worker.submit(lambda: self.publish(self._timed(job), counts))

    def _timed(self, job: Callable[[], jobs.EstimateOutputs]) -> jobs.EstimateOutputs:
        """On the worker thread: run an estimate job and record how long it took; a job that fails
        unexpectedly gives an invalid estimate (published, not lost) and a logged traceback."""
        started = time.perf_counter()
        try:
            outputs = job()
        except Exception as exc:
            self.node.get_logger().exception("estimate failed")
            document = invalid_document(self.options.method, f"internal error: {exc!r}")
            document["mode"] = self.mode
            outputs = jobs.outputs_from_document(document, self.node.now_ns(), with_passive=False)
        self.update_s.append(time.perf_counter() - started)
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
        level = OK if outputs.valid else (WARN if "waiting" in outputs.message else ERROR)
        timing = {}
        if self.update_s:  # how long an update takes: near the period, the node cannot keep up
            timing = {
                "update_ms_mean": f"{1e3 * np.mean(self.update_s):.1f}",
                "update_ms_max": f"{1e3 * max(self.update_s):.1f}",
            }
        values = {**counts, "published": self.published, "updates_dropped": self.worker.dropped, **timing}
        status = DiagnosticStatusData.with_values(level, NAME, outputs.message, "", values)
        diagnostics = DiagnosticArraySample(self.node.now_ns(), "", (status,))
        self.diag_pub.publish(build_diagnostic_array(self.types, diagnostics))


def main(args: list[str] | None = None) -> int:
    """Console entry point."""
    return run_node(BspIdentifierNode, NAME, args=args)


if __name__ == "__main__":
    sys.exit(main())
