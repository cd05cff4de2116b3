"""Starts the node suite as separate processes on a private ROS domain and listens to its estimates (rclpy)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from collections.abc import Callable
from typing import Any

from bsp_ros.live.runtime.ros import Client


def wrench_frame_parameter(roll_pitch_yaw_deg: tuple[float, float, float] = (180.0, 0.0, 30.0)) -> str:
    """``wrench_frame_rotation_xyzw:=[...]`` of a simulated sensor frame (the identifier's source without tf2_msgs;
    where tf2_msgs is installed the identifier reads /tf_static instead and ignores it)."""
    from bsp_ros.core.simulation import rotation_from_rpy_deg
    from msg_adapters.rotation import quaternion_from_matrix

    xyzw = quaternion_from_matrix(rotation_from_rpy_deg(*roll_pitch_yaw_deg))
    return "wrench_frame_rotation_xyzw:=[" + ", ".join(repr(float(v)) for v in xyzw) + "]"


Estimates = list[tuple[float, dict[str, Any]]]


#: The outputs of a further identifier that would mix with the first one's, moved under its node name.
IDENTIFIER_OUTPUTS = ("bsp/estimate_json", "bsp/estimate", "bsp/precision_reached", "bsp/weight_support")


class LiveCell:
    """The cell simulator, joint angle estimator and identifier on one domain, plus an in-process listener.

    ``more_identifiers`` (node name -> parameters) starts further bsp_identifier processes on the same simulated
    session, each under its own node name, with the outputs of :data:`IDENTIFIER_OUTPUTS` and its ``/diagnostics``
    under that name (``<name>/estimate_json``, ``<name>/diagnostics``: :meth:`topic_of`); their estimates are
    collected in ``estimates_of[name]``. Tests that differ in the identifier's settings only (a test and its control,
    tests of different outputs) so see one and the same session. ``before_start`` is called with the cell before any
    node starts (to subscribe to what must be heard from the first message on).
    """

    def __init__(
        self,
        domain: int,
        simulator_params: list[str],
        identifier_params: list[str] | None = None,
        more_identifiers: dict[str, list[str]] | None = None,
        before_start: Callable[[LiveCell], None] | None = None,
    ) -> None:
        self.domain = domain
        self.env = {**os.environ, "ROS_DOMAIN_ID": str(domain)}
        self.client = Client("test_listener", domain)
        self.estimates: Estimates = []
        self.estimates_of: dict[str, Estimates] = {}
        self.truth: dict[str, Any] = {}
        self.client.subscribe("std_msgs/msg/String", "bsp/estimate_json", self._collector(self.estimates), "estimates")
        self.client.subscribe(
            "std_msgs/msg/String", "sim/truth", lambda m: self.truth.update(json.loads(m.data)), "tf_static_listener"
        )
        for name in more_identifiers or {}:
            self.estimates_of[name] = []
            topic = self.topic_of(name, "bsp/estimate_json")
            self.client.subscribe("std_msgs/msg/String", topic, self._collector(self.estimates_of[name]), "estimates")
        self.simulator_params = simulator_params
        self.processes: dict[str, subprocess.Popen[bytes]] = {}
        if before_start is not None:
            before_start(self)
        self.start("joint_angle_estimator", [])
        self.start("bsp_identifier", _with_rotation(identifier_params))
        for name, params in (more_identifiers or {}).items():
            remaps = [f"{topic}:={self.topic_of(name, topic)}" for topic in (*IDENTIFIER_OUTPUTS, "/diagnostics")]
            self.start("bsp_identifier", _with_rotation(params), [f"__node:={name}", *remaps], key=name)
        self.start("cell_simulator", simulator_params)

    @staticmethod
    def topic_of(identifier: str, topic: str) -> str:
        """Where a further identifier named ``identifier`` publishes what the first one publishes on ``topic``."""
        return f"{identifier}/{topic.rsplit('/', 1)[-1]}"

    @staticmethod
    def _collector(estimates: Estimates) -> Any:
        def on_estimate(msg: Any) -> None:
            estimates.append((time.monotonic(), json.loads(msg.data)))

        return on_estimate

    def start(self, name: str, params: list[str], remaps: list[str] | None = None, key: str | None = None) -> None:
        """Start node ``name`` with parameter overrides and remapping rules; ``key`` names the process (default
        ``name``) for :meth:`kill`."""
        pairs = [("-p", p) for p in params] + [("-r", r) for r in remaps or []]
        args = ["--ros-args", *[a for pair in pairs for a in pair]] if pairs else []
        self.processes[key or name] = subprocess.Popen(
            [sys.executable, "-m", f"bsp_ros.live.nodes.{name}", *args],
            env=self.env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )

    def kill(self, name: str) -> None:
        self.processes[name].kill()
        self.processes[name].wait(5)

    def spin_until(self, predicate: Any, timeout_s: float) -> bool:
        return self.client.spin_until(predicate, timeout_s)

    def latest(self) -> dict[str, Any] | None:
        return self.estimates[-1][1] if self.estimates else None

    def close(self) -> None:
        for process in self.processes.values():
            process.kill()
        for process in self.processes.values():
            process.wait(5)
        self.client.close()


def _with_rotation(identifier_params: list[str] | None) -> list[str]:
    """The identifier's parameters with the default simulated sensor rotation unless they give one."""
    params = list(identifier_params or [])
    if not any(p.startswith("wrench_frame_rotation_xyzw:=") for p in params):
        params.append(wrench_frame_parameter())
    return params
