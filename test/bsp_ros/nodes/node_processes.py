"""Nodes as separate processes on a private DDS domain, and an in-process listener/publisher on that domain."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bsp_ros.runtime import make_context

ROOT = Path(__file__).resolve().parents[3]
PLAY_PEER = ROOT / "test" / "bsp_ros" / "play_record_peer.py"


#: Offsets of :func:`domain_id` in use, one per test (a killed node lingers in DDS discovery until its lease ends):
#: test_replay_identify 0, test_session_recorder 1-4.
DOMAIN_OFFSETS = 5


def domain_id(offset: int, base: int = 11, slots: int = 44) -> int:
    """A DDS domain id unique to this test process and ``offset``; Cyclone allows 0..232."""
    assert 0 <= offset < DOMAIN_OFFSETS
    return base + (os.getpid() % slots) * DOMAIN_OFFSETS + offset


class NodeProcesses:
    """bsp_ros nodes (``python -m bsp_ros.nodes.<name>``) on one domain; their stderr goes to ``log_dir``."""

    def __init__(self, domain: int, log_dir: Path) -> None:
        self.domain = domain
        self.log_dir = log_dir
        self.env = {
            **os.environ,
            "BSP_ROS_BACKEND": "dds",
            "ROS_DOMAIN_ID": str(domain),
            "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
        }
        self.processes: dict[str, subprocess.Popen[bytes]] = {}

    def start(self, name: str, params: list[str]) -> subprocess.Popen[bytes]:
        """Start node ``name`` with ``--param`` overrides (``name:=value``)."""
        args = [a for p in params for a in ("--param", p)]
        with open(self.log_dir / f"{name}.log", "ab") as log:
            process = subprocess.Popen(
                [sys.executable, "-m", f"bsp_ros.nodes.{name}", *args],
                env=self.env,
                stdout=subprocess.DEVNULL,
                stderr=log,
            )
        self.processes[name] = process
        return process

    def play(self, bag: Path, *args: object) -> subprocess.Popen[str]:
        """``bsp play BAG ARGS`` on this domain (stdout piped)."""
        return subprocess.Popen(
            [sys.executable, str(PLAY_PEER), "play", str(bag), "--domain", str(self.domain), *map(str, args)],
            env=self.env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )

    def log(self, name: str) -> str:
        """What node ``name`` wrote on stderr so far."""
        path = self.log_dir / f"{name}.log"
        return path.read_text("utf-8", errors="replace") if path.exists() else ""

    def close(self) -> None:
        """Stop every node started here: SIGINT (a clean exit leaves DDS discovery at once), then SIGKILL."""
        for process in self.processes.values():
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
        for process in self.processes.values():
            try:
                process.wait(3)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(5)


class Peer:
    """An in-process DDS node on the domain: JSON topics it listens to, publishers it owns."""

    def __init__(self, domain: int, name: str = "test_peer") -> None:
        self.context = make_context("dds", domain_id=domain, args=[])
        self.node = self.context.create_node(name)
        self.received: dict[str, list[tuple[float, dict[str, Any]]]] = {}

    def listen_json(self, topic: str, qos: str = "estimates") -> list[tuple[float, dict[str, Any]]]:
        """Collect (monotonic receive time, parsed JSON) of every std_msgs/String on ``topic``."""
        out = self.received.setdefault(topic, [])

        def on_message(msg: Any) -> None:
            out.append((time.monotonic(), json.loads(msg.data)))

        self.node.create_subscription("std_msgs/msg/String", topic, on_message, qos)
        return out

    def string_publisher(self, topic: str, qos: str = "estimates") -> Callable[[str], None]:
        """A function publishing its argument as a std_msgs/String on ``topic``; ``.publisher`` is the writer."""
        publisher = self.node.create_publisher("std_msgs/msg/String", topic, qos)
        cls = self.node.message_class("std_msgs/msg/String")

        def publish(text: str) -> None:
            publisher.publish(cls(data=text))

        publish.publisher = publisher  # type: ignore[attr-defined]
        return publish

    def spin_until(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Run callbacks until ``predicate()`` or the timeout; return whether it held."""
        deadline = time.monotonic() + timeout_s
        while True:
            if predicate():
                return True
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return False
            self.context.spin(min(0.1, remaining))

    def close(self) -> None:
        """Shut the context down."""
        self.context.shutdown()
