"""`session_recorder`: stores the final valid live estimate of a session in the session store, once."""

from __future__ import annotations

import json
import sys
from typing import Any

from bsp_ros.clinic.store import check_subject_id, open_store
from bsp_ros.errors import BspError
from bsp_ros.live.runtime.parameters import Param, declare_parameters
from bsp_ros.live.runtime.qos import rclpy_qos
from bsp_ros.live.runtime.ros import RosNode, message_class
from bsp_ros.live.runtime.spin import run_node
from bsp_ros.live.session_end import SessionEndDetector

NAME = "session_recorder"


PARAMETERS = (
    Param("subject", "", "pseudonymous subject id (required)"),
    Param("store", "", "store file or postgresql:// URL (empty: the per-user default)"),
    Param("end_timeout_s", 5.0, "estimates silent this long end the session", "s", lo=0.5, hi=3600.0),
)


class SessionRecorderNode(RosNode):
    """Listens to `bsp/estimate_json`; on the end of a session stores its last valid estimate.

    The end is silence on the estimate topic for ``end_timeout_s`` or any message on `bsp/session_end`.
    The subject is a pseudonymous id (a parameter): never a name.
    """

    def __init__(self) -> None:
        super().__init__(NAME)
        p = declare_parameters(self, PARAMETERS)
        self.subject = check_subject_id(p["subject"])
        self.store_location = p["store"] or None
        self.detector = SessionEndDetector(p["end_timeout_s"])
        self.end_requested = False
        self.stored_ids: list[int] = []
        string = message_class("std_msgs/msg/String")
        self.create_subscription(string, "bsp/estimate_json", self.on_estimate, rclpy_qos("estimates"))
        self.create_subscription(string, "bsp/session_end", self.on_end, rclpy_qos("estimates"))
        self.create_timer(0.5, self.on_timer)

    def now_ns(self) -> int:
        """The node clock, ns."""
        return int(self.get_clock().now().nanoseconds)

    def on_estimate(self, msg: Any) -> None:
        """Track an estimate."""
        try:
            document = json.loads(msg.data)
        except ValueError:
            self.get_logger().warning("bsp/estimate_json: not JSON, ignored")
            return
        self.detector.on_estimate(document, self.now_ns())

    def on_end(self, msg: Any) -> None:
        """An explicit end of session."""
        self.end_requested = True
        self.on_timer()

    def on_timer(self) -> None:
        """Store the session's final valid estimate when it ends."""
        document = self.detector.due(self.now_ns(), self.end_requested)
        self.end_requested = False
        if document is None:
            return
        session = document.get("session", {})
        try:
            with open_store(self.store_location) as store:
                record = store.add_estimate(
                    document,
                    self.subject,
                    session_time_ns=session.get("start_time_ns") or self.now_ns(),
                    source=session.get("source", "live"),
                )
        except BspError as error:  # a refused estimate must not stop the recorder of later sessions
            self.get_logger().error(f"session not stored: {error}")
            return
        if record.id is not None:
            self.stored_ids.append(record.id)
        self.get_logger().info(f"stored session {record.id} of subject {self.subject}")


def main(args: list[str] | None = None) -> int:
    """Console entry point (``ros2 run bsp_ros session_recorder``); ``args``: a command line like ``sys.argv``."""
    return run_node(NAME, SessionRecorderNode, SessionRecorderNode.__doc__ or "", PARAMETERS, args)


if __name__ == "__main__":
    sys.exit(main())
