"""A cell's own nodes, written with plain rclpy (no bsp_ros code): an arm of known segments (plain_arm.py), its
wrench and markers out, `/bsp/estimate` in, checked against the truth. Exit 0 if the estimate matches, 1 if not.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np
import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped, WrenchStamped
from plain_arm import MARKERS, angles_rad, motion, points_m, static_moments_kgm, wrench_yzx
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data


class PlainCell(Node):
    def __init__(self, seed: int) -> None:
        super().__init__("plain_rclpy_cell")
        self.rng = np.random.default_rng(seed)
        self.start = time.monotonic()
        self.wrench_pub = self.create_publisher(WrenchStamped, "/ft_sensor/wrench", qos_profile_sensor_data)
        self.marker_pubs = {
            name: self.create_publisher(PoseStamped, f"/mocap/{name}", qos_profile_sensor_data) for name in MARKERS
        }
        self.estimate: dict[str, dict[str, str]] = {}
        self.create_subscription(DiagnosticArray, "/bsp/estimate", self.on_estimate, 10)
        self.create_timer(0.01, self.on_wrench_tick)
        self.create_timer(0.02, self.on_marker_tick)

    def _stamp(self, msg: WrenchStamped | PoseStamped, frame_id: str) -> float:
        now = self.get_clock().now()
        msg.header.stamp = now.to_msg()
        msg.header.frame_id = frame_id
        return time.monotonic() - self.start

    def on_wrench_tick(self) -> None:
        msg = WrenchStamped()
        t_s = self._stamp(msg, "world")
        fy, fz, mx = wrench_yzx(*motion(t_s)) + self.rng.normal(0.0, [0.05, 0.05, 0.005])
        msg.wrench.force.y, msg.wrench.force.z, msg.wrench.torque.x = float(fy), float(fz), float(mx)
        self.wrench_pub.publish(msg)

    def on_marker_tick(self) -> None:
        stamp_msg = PoseStamped()
        t_s = self._stamp(stamp_msg, "world")
        for name, point in zip(MARKERS, points_m(angles_rad(t_s)), strict=True):
            msg = PoseStamped()
            msg.header = stamp_msg.header
            x, y, z = point + self.rng.normal(0.0, 0.0005, 3)
            msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = float(x), float(y), float(z)
            msg.pose.orientation.w = 1.0
            self.marker_pubs[name].publish(msg)

    def on_estimate(self, msg: DiagnosticArray) -> None:
        self.estimate = {status.name: {kv.key: kv.value for kv in status.values} for status in msg.status}

    def valid(self) -> bool:
        return self.estimate.get("bsp/quality", {}).get("valid") == "True"


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--timeout", type=float, default=120.0)
    parser.add_argument("--settle", type=float, default=10.0, help="keep going this long after the first valid one")
    args = parser.parse_args()
    rclpy.init()
    node = PlainCell(seed=11)
    try:
        deadline = time.monotonic() + args.timeout
        while time.monotonic() < deadline and not node.valid():
            rclpy.spin_once(node, timeout_sec=0.05)
        settle_until = time.monotonic() + args.settle
        while time.monotonic() < min(settle_until, deadline):
            rclpy.spin_once(node, timeout_sec=0.05)
        truth = dict(zip(("upper_arm", "forearm", "hand"), static_moments_kgm().tolist(), strict=True))
        imported = any(name.split(".")[0] in ("bsp_ros", "msg_adapters") for name in sys.modules)
        result = {"valid": node.valid(), "truth": truth, "estimate": {}, "std": {}, "bsp_ros_imported": imported}
        for segment in truth:
            values = node.estimate.get(f"bsp/{segment}", {})
            if "static_moment_kgm" in values:
                result["estimate"][segment] = float(values["static_moment_kgm"])
                result["std"][segment] = float(values["static_moment_kgm.std"])
        print(json.dumps(result), flush=True)
        ok = result["valid"] and len(result["estimate"]) == 3 and not imported
        for segment, true in truth.items():
            if ok:
                error = abs(result["estimate"][segment] - true)
                ok = error < max(4 * result["std"][segment], 0.02 * true)
        return 0 if ok else 1
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    sys.exit(main())
