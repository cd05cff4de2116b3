"""`cell_simulator`: the simulated cell (its frames, topics and sensor mounting from the cell file) publishing wrench,
marker poses, the sensor's transform (TransformStamped; /tf_static or /tf where tf2_msgs is installed), truth."""

from __future__ import annotations

import collections
import dataclasses
import json
import os
import sys
from collections.abc import Callable
from typing import Any

import numpy as np

from bsp_ros.cell import CellDescription
from bsp_ros.core import simulation as sim
from bsp_ros.errors import InputError
from bsp_ros.live.runtime.cell_parameters import CELL_FILE, SIMULATOR_FROM_CELL, declare_with_cell
from bsp_ros.live.runtime.parameters import Param
from bsp_ros.live.runtime.qos import rclpy_qos
from bsp_ros.live.runtime.ros import RosNode, has_message, message_class
from bsp_ros.live.runtime.spin import run_node
from msg_adapters.pose import PoseSample, build_pose_stamped
from msg_adapters.rotation import quaternion_from_matrix
from msg_adapters.tf import TransformSample, build_tf_message, build_transform_stamped
from msg_adapters.wrench import WrenchSample, build_wrench_stamped

NAME = "cell_simulator"
TF_TYPE = "tf2_msgs/msg/TFMessage"

PARAMETERS = (
    CELL_FILE,
    Param(
        name="subject",
        default="human",
        description="simulated arm: human (3 segments) or paper-arm (2 segments)",
        choices=("human", "paper-arm"),
    ),
    Param(name="seed", default=0, description="random seed", lo=0, hi=2**31 - 1),
    Param(name="speed", default=1.0, description="simulated seconds per wall second", unit="", lo=0.01, hi=100.0),
    Param(name="wrench_hz", default=100.0, description="wrench rate", unit="Hz", lo=1.0, hi=5000.0),
    Param(name="marker_hz", default=50.0, description="marker rate", unit="Hz", lo=1.0, hi=1000.0),
    Param(
        name="duration_s", default=0.0, description="simulated session length (0: endless)", unit="s", lo=0.0, hi=1e6
    ),
    Param(name="dropout_fraction", default=0.0, description="share of marker frames lost", unit="", lo=0.0, hi=0.9),
    Param(
        name="nan_burst_period_s", default=0.0, description="a NaN burst every this many s (0: none)", unit="s", lo=0.0
    ),
    Param(name="nan_burst_s", default=0.2, description="length of a NaN burst", unit="s", lo=0.0, hi=10.0),
    Param(
        name="stall_at_s",
        default=0.0,
        description="the sensor stops publishing at this time (0: never)",
        unit="s",
        lo=0.0,
    ),
    Param(name="die_at_s", default=0.0, description="the process exits at this time (0: never)", unit="s", lo=0.0),
    Param(
        name="clock_jump_at_s",
        default=0.0,
        description="stamps jump backwards at this time (0: never)",
        unit="s",
        lo=0.0,
    ),
    Param(name="clock_jump_s", default=10.0, description="size of the backwards jump", unit="s", lo=0.0, hi=1e6),
    Param(
        name="sensor_roll_pitch_yaw_deg",
        default=[180.0, 0.0, 30.0],
        description="fixed-axis roll, pitch, yaw of the sensor frame in world (default: the cell file's mounting)",
        unit="deg",
    ),
    Param(
        name="force_bias_n",
        default=[0.0, 0.0, 0.0],
        description="sensor force offset, sensor frame (an imperfect tare)",
        unit="N",
    ),
    Param(
        name="force_drift_n_per_s",
        default=[0.0, 0.0, 0.0],
        description="sensor force offset drift, sensor frame",
        unit="N/s",
    ),
    Param(
        name="handle_mass_kg",
        default=0.0,
        description="handle mass between sensor and hand",
        unit="kg",
        lo=0.0,
        hi=10.0,
    ),
    Param(name="handle_com_m", default=[0.0, 0.0, 0.0], description="handle centre of mass, sensor frame", unit="m"),
    Param(
        name="spike_fraction",
        default=0.0,
        description="share of wrench samples that are spikes",
        unit="",
        lo=0.0,
        hi=0.5,
    ),
    Param(
        name="marker_jump_at_s",
        default=0.0,
        description="one frame of marker_jump_name jumps at this time (0: never)",
        unit="s",
        lo=0.0,
    ),
    Param(name="marker_jump_name", default="elbow", description="the marker of the one-frame jump"),
    Param(
        name="marker_jump_m",
        default=[0.0, 0.67, 0.0],
        description="the one-frame jump (a swapped marker moves ~0.67 m), world",
        unit="m",
    ),
    Param(
        name="passive_offset_nm", default=[0.0], description="elastic passive offset per joint ([0.0]: none)", unit="Nm"
    ),
    Param(
        name="friction_transition_rad_s",
        default=0.0,
        description="width of a smooth (tanh) friction transition",
        unit="rad/s",
        lo=0.0,
        hi=1.0,
    ),
    Param(
        name="trajectory_file",
        default="",
        description="follow a `bsp plan` trajectory (JSON or CSV) instead of the built-in motion",
    ),
    Param(
        name="inertia",
        default=True,
        description="rigid-body dynamics (false: quasi-static, as the method paper models it)",
    ),
    Param(
        name="sensor_turns",
        default=False,
        description="the sensor turns with the handle's pitch; its orientation goes on /tf per sample",
    ),
    Param(
        name="transform_topic",
        default="",
        description="also publish the sensor frame's transform in world as geometry_msgs/TransformStamped here: per "
        "wrench sample if it turns, else at the start and once a second (default: the cell file's transform topic; '': "
        "not)",
    ),
    Param(
        name="wrench_filter_delay_s",
        default=0.0,
        description="group delay of the sensor's causal low-pass (0: none)",
        unit="s",
        lo=0.0,
        hi=1.0,
    ),
    Param(
        name="wrench_filter",
        default="first_order",
        description="the sensor's low-pass",
        choices=("first_order", "moving_average"),
    ),
    Param(
        name="wrench_clock_offset_s",
        default=0.0,
        description="wrench stamps lag the marker clock by this much",
        unit="s",
        lo=-1.0,
        hi=1.0,
    ),
    Param(
        name="skin_offset_mm",
        default=0.0,
        description="skin markers re-placed per session within +- this per axis",
        unit="mm",
        lo=0.0,
        hi=100.0,
    ),
    Param(
        name="hand_marker_offset_mm",
        default=[0.0, 0.0],
        description="the hand marker sits this far from the contact point (along, normal to the hand: on the back of "
        "the hand)",
        unit="mm",
    ),
    Param(
        name="robot_handle_pose",
        default=False,
        description="the robot publishes the contact point on /robot/handle_pose per wrench sample",
    ),
    Param(name="wrench_topic", default="/ft_sensor/wrench", description="WrenchStamped topic"),
    Param(name="marker_topic_prefix", default="/mocap/", description="PoseStamped topics: prefix + marker name"),
    # A real sensor driver publishes each sample as it is measured; the default 1 ms tick comes close at
    # 1 kHz (a coarser tick publishes bursts, which delay the last sample of each burst downstream).
    Param(
        name="tick_s",
        default=0.001,
        description="publish the samples that fell due every this long",
        unit="s",
        lo=0.0005,
        hi=0.1,
    ),
    Param(
        name="wait_for_subscribers",
        default=0,
        description="start the session once the wrench topic has this many subscribers (at most 10 s later; 0: at "
        "once)",
        lo=0,
        hi=100,
    ),
)

# How long the session waits for wait_for_subscribers before it starts anyway.
SUBSCRIBER_WAIT_NS = 10_000_000_000


@dataclasses.dataclass
class _Queue:
    """Messages simulated ahead, (simulated time ns, message), and the next time to simulate."""

    next_ns: int
    items: collections.deque[tuple[int, Any]] = dataclasses.field(default_factory=collections.deque)


@dataclasses.dataclass(frozen=True, kw_only=True, eq=False)
class CellFaults:
    """The faults the simulated cell injects on request; times are simulated seconds since the start (0: never).

    Attributes
    ----------
    nan_burst_period_s : a NaN burst in the wrench's force every this many s.
    nan_burst_s : length of each burst, s.
    stall_at_s : the sensor stops publishing the wrench at this time.
    die_at_s : the process exits (code 3) at this time.
    clock_jump_at_s : stamps jump backwards at this time (the physics keeps going).
    clock_jump_s : size of that jump, s.
    marker_jump_at_s : one frame of ``marker_jump_name`` jumps at this time.
    marker_jump_name : the marker of the one-frame jump.
    marker_jump_m : (3,) the jump in world, m.
    """

    nan_burst_period_s: float
    nan_burst_s: float
    stall_at_s: float
    die_at_s: float
    clock_jump_at_s: float
    clock_jump_s: float
    marker_jump_at_s: float
    marker_jump_name: str
    marker_jump_m: np.ndarray

    @classmethod
    def from_parameters(cls, p: dict[str, Any]) -> CellFaults:
        """The faults of the node's parameter values ``p``.

        Raises
        ------
        InputError
            If ``marker_jump_m`` is not 3 finite coordinates.
        """
        marker_jump_m = np.asarray(p["marker_jump_m"], dtype=float)
        if marker_jump_m.shape != (3,) or not np.isfinite(marker_jump_m).all():
            raise InputError(f"{NAME}: marker_jump_m needs 3 finite coordinates, got {p['marker_jump_m']}")
        return cls(
            nan_burst_period_s=p["nan_burst_period_s"],
            nan_burst_s=p["nan_burst_s"],
            stall_at_s=p["stall_at_s"],
            die_at_s=p["die_at_s"],
            clock_jump_at_s=p["clock_jump_at_s"],
            clock_jump_s=p["clock_jump_s"],
            marker_jump_at_s=p["marker_jump_at_s"],
            marker_jump_name=p["marker_jump_name"],
            marker_jump_m=marker_jump_m,
        )


def cell_spec_from_parameters(p: dict[str, Any], cell: CellDescription, start_ns: int) -> sim.CellSpec:
    """The simulated cell the node's parameter values ``p`` describe, in the frames of ``cell``.

    Parameters
    ----------
    p : the node's parameter values (``PARAMETERS``, the cell's defaults applied).
    cell : the cell description; its sensor frame names the wrench's frame.
    start_ns : the physics' start on its own clock, ns.

    Returns
    -------
    The subject's default cell with the parameters' sensor, markers, passive moments and motion; at least 1 s
    long (``duration_s`` 0 is an endless session).

    Raises
    ------
    InputError
        If ``sensor_roll_pitch_yaw_deg`` is not 3 angles, ``hand_marker_offset_mm`` not 2 offsets, or
        ``trajectory_file`` cannot be read.
    """
    rpy = p["sensor_roll_pitch_yaw_deg"]
    if len(rpy) != 3:
        raise InputError(f"{NAME}: sensor_roll_pitch_yaw_deg needs 3 angles, got {rpy}")
    base = sim.human_arm_cell() if p["subject"] == "human" else sim.paper_mechanical_arm_cell()
    hand_offset = p["hand_marker_offset_mm"]
    if len(hand_offset) != 2:
        raise InputError(f"{NAME}: hand_marker_offset_mm needs 2 offsets (along, normal), got {hand_offset}")
    n_markers = base.n_segments + 1
    skin_offset_m = ((0.0, 0.0),) * (n_markers - 1) + ((hand_offset[0] / 1000.0, hand_offset[1] / 1000.0),)
    spec = dataclasses.replace(
        base,
        seed=p["seed"],
        start_ns=start_ns,
        duration_s=max(p["duration_s"], 1.0),
        sensor=dataclasses.replace(
            base.sensor,
            frame_id=cell.sensor_frame,
            wrench_hz=p["wrench_hz"],
            roll_pitch_yaw_deg=tuple(rpy),
            force_bias_n=tuple(p["force_bias_n"]),
            force_drift_n_per_s=tuple(p["force_drift_n_per_s"]),
            handle_mass_kg=p["handle_mass_kg"],
            handle_com_m=tuple(p["handle_com_m"]),
            spike_fraction=p["spike_fraction"],
            turns_with_handle=p["sensor_turns"],
            filter_delay_s=p["wrench_filter_delay_s"],
            filter_kind=p["wrench_filter"],
            clock_offset_s=p["wrench_clock_offset_s"],
        ),
        markers=dataclasses.replace(
            base.markers,
            marker_hz=p["marker_hz"],
            dropout_fraction=p["dropout_fraction"],
            skin_offset_bound_m=p["skin_offset_mm"] / 1000.0,
            skin_offset_m=skin_offset_m if any(hand_offset) else base.markers.skin_offset_m,
        ),
        inertia=p["inertia"],
        passive=dataclasses.replace(
            base.passive,
            offset_nm=tuple(p["passive_offset_nm"]) if any(p["passive_offset_nm"]) else (),
            friction_transition_rad_s=p["friction_transition_rad_s"],
        ),
    )
    if p["trajectory_file"]:
        from bsp_ros.core.planning import planned_trajectory_from_file

        spec = dataclasses.replace(spec, trajectory=planned_trajectory_from_file(p["trajectory_file"]))
    return spec


class CellSimulatorNode(RosNode):
    """Paces :class:`bsp_ros.core.simulation.CellSimulator` against the clock and publishes its streams.

    The physics (inertia, a sensor turning with the handle, its filter and clock, skin markers) is the
    core's. Its frames, topics and the sensor's mounting are the cell file's (``cell_file``, the shipped cell
    when unset), as the other nodes and `bsp record` / `bsp play` read them. The sensor frame's transform goes
    out as TransformStamped on ``transform_topic`` (the cell file's; once a second, or with every wrench sample
    of a turning sensor) and, where tf2_msgs is installed, on /tf_static (or /tf when it turns); the node logs
    the (mounting) quaternion either way. Faults on request
    (parameters): marker dropouts, a one-frame marker jump, NaN bursts in the wrench, a stalled sensor (stops
    publishing the wrench), a dying process, and a backwards clock jump of the stamps.
    """

    def __init__(self) -> None:
        super().__init__(NAME)
        p, cell = declare_with_cell(self, PARAMETERS, SIMULATOR_FROM_CELL)
        self.world_frame = cell.world_frame
        self.speed = p["speed"]
        self.duration_s = p["duration_s"]
        self.faults = CellFaults.from_parameters(p)
        self.marker_jumped = False
        wrench_hz, marker_hz = p["wrench_hz"], p["marker_hz"]
        # The physics runs on its own clock from sim_start_ns; the session starts on the node clock at the first
        # tick (start_wall_ns), once its subscribers are there, and every stamp is shifted by the difference.
        # Building the simulator takes a noticeable part of a second: starting the clock before it made the first
        # tick publish that time's samples in one burst, while the subscribers had not matched yet.
        self.sim_start_ns = self.now_ns()
        self.start_wall_ns: int | None = None
        self.wait_for_subscribers = p["wait_for_subscribers"]
        spec = cell_spec_from_parameters(p, cell, self.sim_start_ns)
        self.simulator = sim.CellSimulator(spec)
        if self.faults.marker_jump_name not in self.simulator.marker_names:
            raise InputError(
                f"{NAME}: marker_jump_name {self.faults.marker_jump_name!r} is not a marker of this arm"
                f" ({', '.join(self.simulator.marker_names)})"
            )
        self.frame_id = spec.sensor.frame_id
        self.wrench_period_ns = int(1e9 / wrench_hz)
        self.marker_period_ns = int(1e9 / marker_hz)
        self.wrench_queue = _Queue(self.sim_start_ns)
        self.marker_queue = _Queue(self.sim_start_ns)
        self.types = message_class
        self._create_stream_publishers(p, cell)
        self.quaternion = quaternion_from_matrix(self.simulator.rotation_world_from_sensor)
        self.turns = spec.sensor.turns_with_handle
        self._create_transform_publishers(p["transform_topic"])
        self.truth_pub = self.create_publisher(
            message_class("std_msgs/msg/String"), "sim/truth", rclpy_qos("tf_static")
        )
        self.create_timer(p["tick_s"], self.tick)
        self.get_logger().info(
            f"simulating a {self.simulator.n_segments}-segment arm at {self.speed:.1f}x real time, "
            f"wrench {wrench_hz:.0f} Hz, markers {marker_hz:.0f} Hz"
        )

    def _create_stream_publishers(self, p: dict[str, Any], cell: CellDescription) -> None:
        """The wrench's, the markers' and (with ``robot_handle_pose``) the contact point's publishers."""
        sensor_data = rclpy_qos("sensor_data")
        self.wrench_pub = self.create_publisher(
            message_class("geometry_msgs/msg/WrenchStamped"), p["wrench_topic"], sensor_data
        )
        pose = message_class("geometry_msgs/msg/PoseStamped")
        self.handle_pose_pub = None  # the contact point from the robot's kinematics, exact
        if p["robot_handle_pose"]:
            topic = cell.handle_pose_topic or "/robot/handle_pose"
            self.handle_pose_pub = self.create_publisher(pose, topic, sensor_data)
        self.marker_pubs = {
            name: self.create_publisher(pose, p["marker_topic_prefix"] + name, sensor_data)
            for name in self.simulator.marker_names
        }

    def _create_transform_publishers(self, transform_topic: str) -> None:
        """The sensor frame's transform publishers (``transform_topic``: TransformStamped, '' for none; /tf or
        /tf_static where tf2_msgs is installed), and the log line that says where its rotation goes."""
        self.tf_pub = None  # /tf of a turning sensor, one transform per wrench sample
        self.static_pub = None  # /tf_static of a fixed one, sent when the session starts
        self.transform_pub = None  # the same as TransformStamped (a robot publishing its flange pose)
        self.transform_sent_ns = 0  # a fixed sensor's transform goes out once a second (late subscribers)
        if transform_topic:
            transform_type = message_class("geometry_msgs/msg/TransformStamped")
            self.transform_pub = self.create_publisher(transform_type, transform_topic, 100)
        where = "/tf (per sample)" if self.turns else "/tf_static"
        if has_message(TF_TYPE):
            if self.turns:
                self.tf_pub = self.create_publisher(message_class(TF_TYPE), "/tf", 100)
            else:
                self.static_pub = self.create_publisher(message_class(TF_TYPE), "/tf_static", rclpy_qos("tf_static"))
        xyzw = [round(float(v), 9) for v in self.quaternion]
        on_topic = f"on {transform_topic} (TransformStamped)" if transform_topic else "on no transform topic"
        self.get_logger().info(
            f"sensor frame {self.frame_id}: rotation {self.world_frame} <- sensor xyzw {xyzw} "
            + ("at the mean handle pitch; " if self.turns else "")
            + on_topic
            + (f" and {where}" if has_message(TF_TYPE) else f" (not on {where}: {TF_TYPE} is not installed)")
        )

    def now_ns(self) -> int:
        """The node clock, ns."""
        return int(self.get_clock().now().nanoseconds)

    def start(self, now_ns: int) -> None:
        """Start the session on the node clock: the transform of a fixed sensor and the truth go out."""
        self.start_wall_ns = now_ns
        if self.static_pub is not None:
            transform = TransformSample(now_ns, self.world_frame, self.frame_id, np.zeros(3), self.quaternion)
            self.static_pub.publish(build_tf_message(message_class, [transform]))
        self._send_fixed_transform(now_ns)
        truth = {**self.simulator.truth.to_dict(), "start_time_ns": now_ns}
        truth["simulation"] = {**truth["simulation"], "start_ns": now_ns}  # the trajectory's t = 0, as stamped
        self.truth_pub.publish(message_class("std_msgs/msg/String")(data=json.dumps(truth)))

    def _sim_now_ns(self, now_ns: int) -> int:
        assert self.start_wall_ns is not None
        return self.sim_start_ns + int((now_ns - self.start_wall_ns) * self.speed)

    def _stamp(self, t_ns: np.ndarray) -> np.ndarray:
        """Simulated times (ns) -> stamps on the node clock, with the clock-jump fault (the physics keeps going)."""
        assert self.start_wall_ns is not None
        stamps = t_ns + np.int64(self.start_wall_ns - self.sim_start_ns)
        if self.faults.clock_jump_at_s > 0:
            jumped = t_ns - self.sim_start_ns >= self.faults.clock_jump_at_s * 1e9
            return np.where(jumped, stamps - int(self.faults.clock_jump_s * 1e9), stamps)
        return stamps

    def tick(self) -> None:
        """Publish every sample whose simulated time has come (the first tick, with its subscribers, starts)."""
        wall_ns = self.now_ns()
        if self.start_wall_ns is None:
            waited = wall_ns - self.sim_start_ns >= SUBSCRIBER_WAIT_NS
            if self.wrench_pub.get_subscription_count() < self.wait_for_subscribers and not waited:
                return
            self.start(wall_ns)
        now = self._sim_now_ns(wall_ns)
        elapsed_s = (now - self.sim_start_ns) / 1e9
        if self.faults.die_at_s and elapsed_s >= self.faults.die_at_s:
            self.get_logger().warning("fault: the simulated sensor dies now")
            os._exit(3)
        if self.duration_s and elapsed_s >= self.duration_s:
            now = min(now, self.sim_start_ns + int(self.duration_s * 1e9))
        stalled = bool(self.faults.stall_at_s and elapsed_s >= self.faults.stall_at_s)
        if wall_ns - self.transform_sent_ns >= 1_000_000_000:
            self._send_fixed_transform(wall_ns)
        wrench_due = self._due(self.wrench_queue, now, self.wrench_period_ns, self._simulate_wrench)
        for wrench, transform, handle in wrench_due:
            if self.handle_pose_pub is not None:  # the robot's kinematics go on when the sensor stalls
                self.handle_pose_pub.publish(build_pose_stamped(self.types, handle))
            if not stalled:
                self.wrench_pub.publish(build_wrench_stamped(self.types, wrench))
            if self.tf_pub is not None:  # the robot still reports its flange when the sensor stalls
                self.tf_pub.publish(build_tf_message(self.types, [transform]))
            if self.transform_pub is not None and transform is not None:  # a turning sensor's, per sample
                self.transform_pub.publish(build_transform_stamped(self.types, transform))
        for name, pose in self._due(self.marker_queue, now, self.marker_period_ns, self._simulate_markers):
            self.marker_pubs[name].publish(build_pose_stamped(self.types, pose))

    def _send_fixed_transform(self, wall_ns: int) -> None:
        """A fixed sensor's transform on the transform topic, stamped now on the stamps' clock."""
        if self.transform_pub is None or self.turns:
            return
        stamp = int(self._stamp(np.array([self._sim_now_ns(wall_ns)], dtype=np.int64))[0])
        transform = TransformSample(stamp, self.world_frame, self.frame_id, np.zeros(3), self.quaternion)
        self.transform_pub.publish(build_transform_stamped(self.types, transform))
        self.transform_sent_ns = wall_ns

    def _due(
        self, queue: _Queue, now_ns: int, period_ns: int, simulate: Callable[[np.ndarray], list[Any]]
    ) -> list[Any]:
        """The queued messages stamped up to ``now_ns``; the physics is simulated ahead in 0.1 s chunks, since
        one vectorised call per sample would cost more than publishing it."""
        while queue.next_ns <= now_ns:
            chunk = np.arange(queue.next_ns, queue.next_ns + max(int(0.1e9), period_ns), period_ns, dtype=np.int64)
            queue.next_ns = int(chunk[-1]) + period_ns
            queue.items.extend(simulate(chunk))
        due = []
        while queue.items and queue.items[0][0] <= now_ns:
            due.append(queue.items.popleft()[1])
        return due

    def _simulate_wrench(self, t_ns: np.ndarray) -> list[tuple[int, Any]]:
        series = self.simulator.sample_wrench(t_ns)
        force, torque = series.force_n.copy(), series.torque_nm.copy()
        if self.faults.nan_burst_period_s > 0:
            phase = ((t_ns - self.sim_start_ns) / 1e9) % self.faults.nan_burst_period_s
            burst = phase > self.faults.nan_burst_period_s - self.faults.nan_burst_s
            force[burst] = np.nan
        stamps = self._stamp(series.t_ns)
        samples = [WrenchSample(int(stamps[k]), self.frame_id, force[k], torque[k]) for k in range(stamps.size)]
        transforms: list[TransformSample | None] = [None] * stamps.size
        if self.turns:
            tf_ns = self.simulator.orientation_stamps_ns(series.t_ns)
            rotations = self.simulator.rotations_world_from_sensor(self.simulator.seconds_since_start(tf_ns))
            tf_stamps = self._stamp(tf_ns)
            transforms = [
                TransformSample(int(t), self.world_frame, self.frame_id, np.zeros(3), quaternion_from_matrix(r))
                for t, r in zip(tf_stamps.tolist(), rotations, strict=True)
            ]
        handles: list[PoseSample | None] = [None] * stamps.size
        if self.handle_pose_pub is not None:
            pose_ns = self.simulator.orientation_stamps_ns(series.t_ns)  # on the marker clock, as the robot's
            contact_m = self.simulator.handle_positions_m(self.simulator.seconds_since_start(pose_ns))
            identity = np.array([0.0, 0.0, 0.0, 1.0])
            handles = [
                PoseSample(int(t), self.world_frame, c, identity)
                for t, c in zip(self._stamp(pose_ns).tolist(), contact_m, strict=True)
            ]
        # Messages are built when published.
        return list(zip(t_ns.tolist(), zip(samples, transforms, handles, strict=True), strict=True))

    def _simulate_markers(self, t_ns: np.ndarray) -> list[tuple[int, tuple[str, Any]]]:
        identity = np.array([0.0, 0.0, 0.0, 1.0])
        out = []
        for name, series in self.simulator.sample_markers(t_ns).items():
            stamps = self._stamp(series.t_ns)
            position_m = self._with_marker_jump(name, series.t_ns, series.position_m)
            for k in range(stamps.size):
                pose = PoseSample(int(stamps[k]), self.world_frame, position_m[k], identity)
                out.append((int(series.t_ns[k]), (name, pose)))
        out.sort(key=lambda item: item[0])  # frames in time order, markers of a frame together
        return out

    def _with_marker_jump(self, name: str, t_ns: np.ndarray, position_m: np.ndarray) -> np.ndarray:
        """Marker ``name``'s (n, 3) positions (m) at simulated times ``t_ns`` (n,) (ns), with the one-frame jump
        fault added to its first frame due, once per session (a swapped or misread marker)."""
        faults = self.faults
        if not (faults.marker_jump_at_s > 0 and not self.marker_jumped and name == faults.marker_jump_name):
            return position_m
        due = np.flatnonzero(t_ns - self.sim_start_ns >= faults.marker_jump_at_s * 1e9)
        if not due.size:
            return position_m
        position_m = position_m.copy()
        position_m[due[0]] += faults.marker_jump_m  # one frame only
        self.marker_jumped = True
        self.get_logger().warning(f"fault: marker {name} jumps by {faults.marker_jump_m} m for one frame")
        return position_m


def main(args: list[str] | None = None) -> int:
    """Console entry point (``ros2 run bsp_ros cell_simulator``); ``args``: a command line like ``sys.argv``."""
    return run_node(NAME, CellSimulatorNode, CellSimulatorNode.__doc__ or "", PARAMETERS, args)


if __name__ == "__main__":
    sys.exit(main())
