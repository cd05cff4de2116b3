"""`session_recorder`: stores the final valid live estimate of a session in the session store, once."""

from __future__ import annotations

import json
import sys
from typing import Any

from bsp_ros.errors import BspError
from bsp_ros.runtime import run_node
from bsp_ros.session_end import SessionEndDetector
from bsp_ros.store import check_subject_id, open_store

NAME = "session_recorder"


class SessionRecorderNode:
    """Listens to `bsp/estimate_json`; on the end of a session stores its last valid estimate.

    The end is silence on the estimate topic for ``end_timeout_s`` or any message on `bsp/session_end`.
    The subject is a pseudonymous id (a parameter): never a name.
    """

    def __init__(self, node: Any) -> None:
        self.node = node
        p = node.declare_parameter
        self.subject = check_subject_id(p("subject", "", "pseudonymous subject id (required)"))
        self.store_location = p("store", "", "store file or postgresql:// URL (empty: the per-user default)") or None
        timeout = p("end_timeout_s", 5.0, "estimates silent this long end the session", "s", lo=0.5, hi=3600.0)
        self.detector = SessionEndDetector(timeout)
        self.end_requested = False
        self.stored_ids: list[int] = []
        node.create_subscription("std_msgs/msg/String", "bsp/estimate_json", self.on_estimate, "estimates")
        node.create_subscription("std_msgs/msg/String", "bsp/session_end", self.on_end, "estimates")
        node.create_timer(0.5, self.on_timer)

    def on_estimate(self, msg: Any) -> None:
        """Track an estimate."""
        try:
            document = json.loads(msg.data)
        except ValueError:
            self.node.get_logger().warning("bsp/estimate_json: not JSON, ignored")
            return
        self.detector.on_estimate(document, self.node.now_ns())

    def on_end(self, msg: Any) -> None:
        """An explicit end of session."""
        self.end_requested = True
        self.on_timer()

    def on_timer(self) -> None:
        """Store the session's final valid estimate when it ends."""
        document = self.detector.due(self.node.now_ns(), self.end_requested)
        self.end_requested = False
        if document is None:
            return
        session = document.get("session", {})
        try:
            with open_store(self.store_location) as store:
                record = store.add_estimate(
                    document,
                    self.subject,
                    session_time_ns=session.get("start_time_ns") or self.node.now_ns(),
                    source=session.get("source", "live"),
                )
        except BspError as error:  # a refused estimate must not stop the recorder of later sessions
            self.node.get_logger().error("session not stored: %s", error)
            return
        if record.id is not None:
            self.stored_ids.append(record.id)
        self.node.get_logger().info("stored session %s of subject %s", record.id, self.subject)


def main(args: list[str] | None = None) -> int:
    """Console entry point."""
    return run_node(SessionRecorderNode, NAME, args=args)


if __name__ == "__main__":
    sys.exit(main())
