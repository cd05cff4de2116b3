"""Nodes as separate processes on a private ROS domain, and an in-process rclpy listener/publisher on it."""

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

from ros_domains import next_domain_id

from bsp_ros.live.runtime.ros import Client

ROOT = Path(__file__).resolve().parents[4]
PLAY_PEER = ROOT / "test" / "bsp_ros" / "live" / "play_record_peer.py"


def domain_id(offset: int = 0) -> int:
    """A fresh ROS domain id for this test process (``offset`` is kept for the callers' readability only)."""
    return next_domain_id()


class NodeProcesses:
    """bsp_ros nodes (``python -m bsp_ros.live.nodes.<name>``) on one domain; their stderr goes to ``log_dir``."""

    def __init__(self, domain: int, log_dir: Path) -> None:
        self.domain = domain
        self.log_dir = log_dir
        self.env = {
            **os.environ,
            "ROS_DOMAIN_ID": str(domain),
            "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""),
        }
        self.processes: dict[str, subprocess.Popen[bytes]] = {}

    def start(self, name: str, params: list[str]) -> subprocess.Popen[bytes]:
        """Start node ``name`` with ROS parameter overrides (``name:=value``)."""
        args = ["--ros-args", *[a for p in params for a in ("-p", p)]] if params else []
        with open(self.log_dir / f"{name}.log", "ab") as log:
            process = subprocess.Popen(
                [sys.executable, "-m", f"bsp_ros.live.nodes.{name}", *args],
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
        """Stop every node started here: SIGINT (a clean exit leaves the ROS graph at once), then SIGKILL."""
        for process in self.processes.values():
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
        for process in self.processes.values():
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(5)


class Peer:
    """An in-process rclpy node on the domain: JSON topics it listens to, publishers it owns."""

    def __init__(self, domain: int, name: str = "test_peer") -> None:
        self.client = Client(name, domain)
        self.received: dict[str, list[tuple[float, dict[str, Any]]]] = {}

    def listen_json(self, topic: str, qos: str = "estimates") -> list[tuple[float, dict[str, Any]]]:
        """Collect (monotonic receive time, parsed JSON) of every std_msgs/String on ``topic``."""
        out = self.received.setdefault(topic, [])

        def on_message(msg: Any) -> None:
            out.append((time.monotonic(), json.loads(msg.data)))

        self.client.subscribe("std_msgs/msg/String", topic, on_message, qos)
        return out

    def string_publisher(self, topic: str, qos: str = "estimates") -> Callable[[str], None]:
        """A function publishing its argument as a std_msgs/String on ``topic``; ``.publisher`` is the writer."""
        from std_msgs.msg import String

        publisher = self.client.publisher("std_msgs/msg/String", topic, qos)

        def publish(text: str) -> None:
            publisher.publish(String(data=text))

        publish.publisher = publisher  # type: ignore[attr-defined]
        return publish

    def spin_until(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Run callbacks until ``predicate()`` or the timeout; return whether it held."""
        return self.client.spin_until(predicate, timeout_s)

    def close(self) -> None:
        """Leave the ROS graph."""
        self.client.close()
