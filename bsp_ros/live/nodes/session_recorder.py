"""`session_recorder`: records each live session of a named subject whole, identifies it and stores it."""

from __future__ import annotations

import sys
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import Any

from bsp_ros.bag import TopicMap
from bsp_ros.bag.topics import TF_TYPE
from bsp_ros.cell import CellDescription
from bsp_ros.clinic.store import is_database_url, open_store
from bsp_ros.clinic.store.location import default_location
from bsp_ros.core.methods import Method
from bsp_ros.errors import InputError
from bsp_ros.live.runtime.cell_parameters import CELL_FILE, FromCell, declare_with_cell
from bsp_ros.live.runtime.parameters import Param
from bsp_ros.live.runtime.qos import rclpy_qos
from bsp_ros.live.runtime.ros import RosNode, has_message, message_class
from bsp_ros.live.runtime.spin import run_node
from bsp_ros.live.session.control import EndCause, Reply, SessionControl, naming_hint
from bsp_ros.live.session.recording import Change, SessionRecording
from bsp_ros.live.session.storing import (
    IdentifySettings,
    SessionJob,
    SessionOutcome,
    add_command,
    add_options_for,
    cell_file_for,
    store_session,
)

NAME = "session_recorder"
SERVICE_TYPE = "std_srvs/srv/Trigger"
#: The services, relative to the node's namespace: what each does is docs/contract.md's.
SERVICES = ("bsp/session/start", "bsp/session/start_retest", "bsp/session/stop", "bsp/session/reset")

PARAMETERS = (
    CELL_FILE,
    Param(
        name="subject",
        default="",
        description="pseudonymous id of the subject whose sessions are recorded (empty: nothing is recorded); may be "
        "set while no session records (ros2 param set)",
    ),
    Param(name="store", default="", description="store file or postgresql:// URL (empty: the per-user default)"),
    Param(
        name="recordings_dir",
        default="",
        description="folder of the session bags (empty: live_recordings beside a SQLite store, else in the per-user "
        "data folder)",
    ),
    Param(
        name="auto_start",
        default=True,
        description="a session starts when the wrench stream starts (else only bsp/session/start)",
    ),
    Param(
        name="end_timeout_s",
        default=5.0,
        description="the wrench stream silent this long ends a session",
        unit="s",
        lo=0.5,
        hi=3600.0,
    ),
    Param(
        name="max_session_s",
        default=1800.0,
        description="a session longer than this ends (and is stored)",
        unit="s",
        lo=1.0,
        hi=14400.0,
    ),
    Param(
        name="keep_recordings",
        default=False,
        description="keep the bag of a valid stored session (else removed; never a failed one's)",
    ),
    Param(name="cell", default="", description="the robot cell's name stored with each session (empty: none)"),
    Param(name="method", default="joint", description="identification method", choices=("joint", "paper")),
    Param(name="passive", default="", description="passive model as `bsp identify --passive` (empty: its default)"),
    Param(name="tare_file", default="", description="tare file of `bsp tare` (empty: none)"),
    Param(
        name="wrench_delay_s",
        default=None,
        description="the wrench delay the cell knows (unset: estimated from the data)",
        unit="s",
        kind=float,
    ),
    Param(
        name="marker_placement_sd_mm", default=2.0, description="skin marker placement sd", unit="mm", lo=0.0, hi=50.0
    ),
    Param(
        name="handle_pose_sd_mm",
        default=0.5,
        description="the robot's contact point registration sd",
        unit="mm",
        lo=0.0,
        hi=50.0,
    ),
    Param(name="wrench_topic", default="/ft_sensor/wrench", description="WrenchStamped topic"),
    Param(name="marker_topic_prefix", default="/mocap/", description="PoseStamped topics: prefix + marker name"),
    Param(
        name="handle_pose_topic",
        default="/robot/handle_pose",
        description="the robot's contact point (PoseStamped; empty: not recorded)",
    ),
    Param(
        name="emg_topic",
        default="/emg/envelope",
        description="the muscles' EMG envelopes (std_msgs/Float32MultiArray; empty: not recorded), recorded where they "
        "stream",
    ),
    Param(
        name="wrench_frame_rotation_xyzw",
        default=[0.0, 0.0, 0.0, 1.0],
        description="rotation world <- wrench frame [x, y, z, w] written into each session's bag metadata where "
        "tf2_msgs is missing, read where the bag records no transform (default: the cell's mounting; the identity: "
        "none)",
    ),
)


#: The parameters whose defaults the cell description gives (as bsp_identifier's and joint_angle_estimator's).
RECORDER_FROM_CELL: FromCell = {
    "wrench_topic": lambda c: c.wrench_topic,
    "marker_topic_prefix": lambda c: c.marker_topic_prefix,
    "handle_pose_topic": lambda c: c.handle_pose_topic,
    "emg_topic": lambda c: c.emg_topic,
    "tare_file": lambda c: "" if c.tare_file is None else str(c.tare_file),
    "wrench_frame_rotation_xyzw": lambda c: [float(v) for v in c.rotation_xyzw],
}


def recordings_dir_for(given: str, store_location: str) -> Path:
    """The folder of the session bags: ``given``, else ``live_recordings`` beside a SQLite store, else beside the
    per-user default store."""
    if given:
        return Path(given).expanduser()
    beside = default_location() if is_database_url(store_location) else store_location
    return Path(beside).expanduser().parent / "live_recordings"


class SessionRecorderNode(RosNode):
    """Records each session of the named subject whole (its wrench, markers, transforms and EMG envelopes where they
    stream, into a bag) and, when it ends, identifies it as `bsp sessions add BAG` would, with the subject record's
    body data, and stores it.

    Sessions start with the service ``bsp/session/start`` (``start_retest``: a same-day retest) or, with
    ``auto_start``, when the wrench stream starts; they end with ``bsp/session/stop``, a message on
    ``bsp/session_end``, the wrench stream silent for ``end_timeout_s``, or ``max_session_s``;
    ``bsp/session/reset`` discards the running session and starts a new one. The subject is a pseudonymous id
    (parameter ``subject``, settable while no session records): never a name, and never in a file name.
    """

    def __init__(self) -> None:
        super().__init__(NAME)
        p, cell = declare_with_cell(
            self, [param for param in PARAMETERS if param.name != "subject"], RECORDER_FROM_CELL
        )
        self._declare_subject()
        self.settings = self._identify_settings(p, cell)
        try:
            self.settings.check()
        except InputError as error:
            raise InputError(
                f"{NAME}: its identification parameters make `bsp identify` options it refuses: {error}"
            ) from None
        with open_store(p["store"] or None) as store:  # a store that cannot be opened stops the node now
            self.store_name = store.location
        self.store_location = p["store"] or None
        self.cell = p["cell"] or None
        self.keep_recordings = p["keep_recordings"]
        with_tf = has_message(TF_TYPE)
        control = SessionControl(
            node_name=NAME,
            end_timeout_s=p["end_timeout_s"],
            max_session_s=p["max_session_s"],
            auto_start=p["auto_start"],
        )
        self.recording = SessionRecording(
            control,
            recordings_dir_for(p["recordings_dir"], self.store_name),
            self.settings.topics,
            with_tf,
            p["wrench_frame_rotation_xyzw"],
            cell,
        )
        self._say_cell(cell, p["wrench_frame_rotation_xyzw"])
        self._name_subject(str(self.get_parameter("subject").value))
        self.add_on_set_parameters_callback(self.on_set_parameters)
        # A whole session takes seconds to identify: off the executor thread, one session at a time.
        self.worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="session_identify")
        self.jobs: list[tuple[SessionJob, Future[SessionOutcome]]] = []
        self.outcomes: list[SessionOutcome] = []
        self._create_interfaces(with_tf)
        self.create_timer(0.25, self.on_timer)

    def _declare_subject(self) -> None:
        """``subject``: the one parameter settable at run time (checked by :meth:`on_set_parameters`)."""
        from rcl_interfaces.msg import ParameterDescriptor

        (subject,) = [param for param in PARAMETERS if param.name == "subject"]
        from rclpy.exceptions import InvalidParameterTypeException

        descriptor = ParameterDescriptor(description=subject.text(), read_only=False)
        try:
            self.declare_parameter("subject", "", descriptor)
        except InvalidParameterTypeException as error:  # subject:=007 is an integer to ROS
            raise InputError(
                f"parameter 'subject' of node {NAME!r} must be a string id ({error}); quote a numeric one: "
                "subject:=\"'007'\""
            ) from None

    @staticmethod
    def _identify_settings(p: dict[str, Any], cell: CellDescription) -> IdentifySettings:
        markers = {name: p["marker_topic_prefix"] + name for name in TopicMap().markers}
        topics = TopicMap(
            wrench=p["wrench_topic"], markers=markers, handle_pose=p["handle_pose_topic"], emg=p["emg_topic"]
        )
        # Without tf2_msgs the cell's TransformStamped topic is recorded: identified with the cell file that names it.
        topics = replace(topics, transform=cell.transform_topic, world_frame=cell.world_frame)
        return IdentifySettings(
            method=Method(p["method"]),
            passive=p["passive"],
            tare_file=p["tare_file"],
            wrench_delay_s=p["wrench_delay_s"],
            marker_placement_sd_mm=p["marker_placement_sd_mm"],
            handle_pose_sd_mm=p["handle_pose_sd_mm"],
            topics=topics,
            cell_file=cell_file_for(cell, p["wrench_frame_rotation_xyzw"], p["tare_file"]),
        )

    def _create_interfaces(self, with_tf: bool) -> None:
        from std_srvs.srv import Trigger

        topics = self.settings.topics
        for topic, type_name in self.recording.types.items():
            if type_name == TF_TYPE and not with_tf:
                continue
            qos_of = {topics.tf_static: "tf_static_listener", topics.tf: "tf", topics.transform: "tf"}
            qos = qos_of.get(topic, "sensor_input")
            self.create_subscription(message_class(type_name), topic, self._on_raw(topic), rclpy_qos(qos), raw=True)
        string = message_class("std_msgs/msg/String")
        self.create_subscription(string, "bsp/session_end", self.on_end_message, rclpy_qos("estimates"))
        handlers = (self.on_start, self.on_start_retest, self.on_stop, self.on_reset)
        for name, handler in zip(SERVICES, handlers, strict=True):
            self.create_service(Trigger, name, handler)

    def now_ns(self) -> int:
        """The node clock, ns."""
        return int(self.get_clock().now().nanoseconds)

    def _say_cell(self, cell: CellDescription, rotation_xyzw: list[float]) -> None:
        """Name the cell file the sessions are recorded and identified with; plainly a warning where its mounting,
        written into each bag without tf2_msgs and used where no transform is recorded, is the shipped simulated
        cell's."""
        import numpy as np

        from bsp_ros.bag.cell_metadata import cell_file_said, is_shipped_cell

        if np.allclose(np.asarray(rotation_xyzw, dtype=np.float64), cell.rotation_xyzw, atol=1e-9):
            log = self.get_logger().warning if is_shipped_cell(cell) else self.get_logger().info
            log(f"cell: {cell_file_said(cell)}")
        else:
            self.get_logger().info(
                f"cell: cell file {cell.source}, the sensor's mounting from parameter wrench_frame_rotation_xyzw"
            )

    # Subject ------------------------------------------------------------------------------------------------
    def _name_subject(self, subject: str) -> None:
        """Take ``subject`` for the next sessions and say where they go (InputError for a bad id)."""
        named = self.recording.control.name_subject(subject)
        if named is None:
            self.get_logger().warning(f"no subject named: nothing is recorded; {naming_hint(NAME)}")
        else:
            self.get_logger().info(f"recording sessions for {named} into {self.store_name}")

    def on_set_parameters(self, params: list[Any]) -> Any:
        """Accept a new ``subject`` if it is pseudonymous and no session of another subject records."""
        from rcl_interfaces.msg import SetParametersResult

        for param in params:
            if param.name == "subject":
                try:
                    self._name_subject(str(param.value))
                except InputError as error:
                    return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    # Input ----------------------------------------------------------------------------------------------------
    def _on_raw(self, topic: str) -> Any:
        def on_message(data: bytes) -> None:
            try:
                change = self.recording.on_message(topic, self.now_ns(), data)
            except OSError as error:
                self._write_failed(error)
                return
            self._apply(change)

        return on_message

    def _write_failed(self, error: OSError) -> None:
        """The bag cannot be written (a full disk): end the session, keeping what was written."""
        path = self.recording.spool.path if self.recording.spool is not None else None
        self.get_logger().error(f"cannot write the session's recording at {path}: {error}")
        try:
            _, change = self.recording.stop(self.now_ns(), EndCause.SHUTDOWN)
        except OSError as again:  # the session has ended; its bag may lack its summary (readable up to the cut)
            self.get_logger().error(f"the recording at {path} could not be closed: {again}")
            return
        self._apply(change)

    # Services and the end message -----------------------------------------------------------------------------
    def _answer(self, result: tuple[Reply, Change], response: Any) -> Any:
        reply, change = result
        self._apply(change)
        response.success, response.message = reply.success, reply.message
        if not reply.success:
            self.get_logger().warning(f"request refused: {reply.message}")
        return response

    def on_start(self, request: Any, response: Any) -> Any:
        """``bsp/session/start``."""
        return self._answer(self.recording.start(self.now_ns()), response)

    def on_start_retest(self, request: Any, response: Any) -> Any:
        """``bsp/session/start_retest``: a session stored as the same day's retest."""
        return self._answer(self.recording.start(self.now_ns(), retest=True), response)

    def on_stop(self, request: Any, response: Any) -> Any:
        """``bsp/session/stop``."""
        return self._answer(self.recording.stop(self.now_ns()), response)

    def on_reset(self, request: Any, response: Any) -> Any:
        """``bsp/session/reset``."""
        return self._answer(self.recording.reset(self.now_ns()), response)

    def on_end_message(self, msg: Any) -> None:
        """A message on ``bsp/session_end`` ends the running session, as ``bsp/session/stop`` does."""
        _, change = self.recording.stop(self.now_ns(), EndCause.END_MESSAGE)
        self._apply(change)

    # Sessions ending, identified off the executor thread --------------------------------------------------------
    def on_timer(self) -> None:
        """End a session by silence or time limit, flush the bag, and log the sessions identified meanwhile."""
        try:
            self._apply(self.recording.tick(self.now_ns()))
        except OSError as error:
            self._write_failed(error)
        control = self.recording.control
        if control.unnamed_input():
            self.get_logger().warning(
                f"the wrench streams in but no subject is named: nothing is recorded; {naming_hint(NAME)}"
            )
        for job, future in [j for j in self.jobs if j[1].done()]:
            self.jobs.remove((job, future))
            outcome = future.result()
            self.outcomes.append(outcome)
            log = self.get_logger().info if outcome.valid else self.get_logger().warning
            log(outcome.log_line())

    def _apply(self, change: Change) -> None:
        """Log what ``change`` did and hand a finished session to the worker."""
        logger = self.get_logger()
        if change.discarded is not None:
            ended, path = change.discarded
            logger.info(f"session of {ended.session.subject} discarded (reset): {path} deleted")
        if change.started is not None:
            started = change.started
            kind = "retest" if started.retest else "session"
            logger.info(f"{kind} of {started.subject} started ({started.cause}), recording into {change.path}")
        if change.finished is None:
            return
        ended, spool = change.finished
        subject = ended.session.subject
        if not ended.stored:
            command = add_command(spool.path, subject, ended.session.retest, add_options_for(self.settings, self.cell))
            logger.warning(
                f"session of {subject} not identified ({ended.cause}); its recording is kept at {spool.path}: add it "
                f"with `{command}`"
            )
            return
        logger.info(f"session of {subject} ended ({ended.cause}, {spool.duration_s:.1f} s): identifying it")
        job = SessionJob(
            ended=ended,
            spool=spool,
            store_location=self.store_location,
            settings=self.settings,
            cell=self.cell,
            keep_recording=self.keep_recordings,
        )
        self.jobs.append((job, self.worker.submit(store_session, job, self.store_name)))

    def destroy_node(self) -> None:
        """Keep a running session's bag (complete, not identified) and finish the identification under way."""
        _, change = self.recording.stop(self.now_ns(), EndCause.SHUTDOWN)
        self._apply(change)
        self.worker.shutdown(wait=True, cancel_futures=True)
        for job, future in self.jobs:
            if future.cancelled():
                path, session = job.spool.path, job.ended.session
                command = add_command(path, session.subject, session.retest, add_options_for(job.settings, job.cell))
                self.get_logger().warning(
                    f"session of {session.subject} not identified (the recorder stopped); its recording is kept at "
                    f"{path}: add it with `{command}`"
                )
            else:
                self.get_logger().info(future.result().log_line())
        self.jobs.clear()
        super().destroy_node()


def main(args: list[str] | None = None) -> int:
    """Console entry point (``ros2 run bsp_ros session_recorder``); ``args``: a command line like ``sys.argv``."""
    return run_node(NAME, SessionRecorderNode, SessionRecorderNode.__doc__ or "", PARAMETERS, args)


if __name__ == "__main__":
    sys.exit(main())
