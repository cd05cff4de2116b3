"""Starts the node suite as separate processes on a private DDS domain and listens to its estimates."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from typing import Any

from bsp_ros.runtime import make_context


class LiveCell:
    """The cell simulator, joint angle estimator and identifier on one domain, plus an in-process listener."""

    def __init__(self, domain: int, simulator_params: list[str], identifier_params: list[str] | None = None) -> None:
        self.domain = domain
        self.env = {**os.environ, "BSP_ROS_BACKEND": "dds", "ROS_DOMAIN_ID": str(domain)}
        self.context = make_context("dds", domain_id=domain, args=[])
        node = self.context.create_node("test_listener")
        self.estimates: list[tuple[float, dict[str, Any]]] = []
        self.truth: dict[str, Any] = {}
        node.create_subscription("std_msgs/msg/String", "bsp/estimate_json", self._on_estimate, "estimates")
        node.create_subscription(
            "std_msgs/msg/String", "sim/truth", lambda m: self.truth.update(json.loads(m.data)), "tf_static_listener"
        )
        self.simulator_params = simulator_params
        self.processes: dict[str, subprocess.Popen[bytes]] = {}
        self.start("joint_angle_estimator", [])
        self.start("bsp_identifier", identifier_params or [])
        self.start("cell_simulator", simulator_params)

    def _on_estimate(self, msg: Any) -> None:
        self.estimates.append((time.monotonic(), json.loads(msg.data)))

    def start(self, name: str, params: list[str]) -> None:
        args = [a for p in params for a in ("--param", p)]
        self.processes[name] = subprocess.Popen(
            [sys.executable, "-m", f"bsp_ros.nodes.{name}", *args],
            env=self.env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )

    def kill(self, name: str) -> None:
        self.processes[name].kill()
        self.processes[name].wait(5)

    def spin_until(self, predicate: Any, timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            self.context.spin(0.2)
            if predicate():
                return True
        return False

    def latest(self) -> dict[str, Any] | None:
        return self.estimates[-1][1] if self.estimates else None

    def close(self) -> None:
        for process in self.processes.values():
            process.kill()
        for process in self.processes.values():
            process.wait(5)
        self.context.shutdown()
