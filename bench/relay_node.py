"""The latency floor of bench_live_latency's recursive row: a node that only relays each wrench's stamp.

Run by ``bench/bench_live_latency.py --modes relay`` in place of ``bsp_identifier``: it takes every wrench on
``/ft_sensor/wrench`` (the identifier's QoS) and at once publishes a JointState on ``bsp/passive_moments`` stamped
with it, on the same rclpy executor, spin loop and interpreter switch interval as the identifier, and its
received count on ``/diagnostics`` (as ``bsp_identifier``, so the bench's loss count reads it). What it measures
is Python rclpy + Fast DDS between two nodes on this machine with the simulator running: no estimator can be
faster.
"""

from __future__ import annotations

import sys
from typing import Any

from bsp_ros.live.runtime.parameters import Param
from bsp_ros.live.runtime.qos import rclpy_qos
from bsp_ros.live.runtime.ros import RosNode, message_class
from bsp_ros.live.runtime.spin import run_node
from msg_adapters.diagnostics import OK, DiagnosticArraySample, DiagnosticStatusData, build_diagnostic_array

NAME = "bsp_identifier"  # the bench waits for, and counts from, this node's /diagnostics


class RelayNode(RosNode):
    """Wrench in, its stamp out as a JointState, nothing computed."""

    def __init__(self) -> None:
        super().__init__("bench_relay")
        self.joint_state = message_class("sensor_msgs/msg/JointState")
        self.out = self.create_publisher(self.joint_state, "bsp/passive_moments", rclpy_qos("estimates"))
        self.diag = self.create_publisher(
            message_class("diagnostic_msgs/msg/DiagnosticArray"), "/diagnostics", rclpy_qos("default")
        )
        wrench = message_class("geometry_msgs/msg/WrenchStamped")
        self.create_subscription(wrench, "/ft_sensor/wrench", self.on_wrench, rclpy_qos("sensor_input"))
        self.received = 0
        self.create_timer(1.0, self.on_watchdog)

    def on_wrench(self, msg: Any) -> None:
        self.received += 1
        out = self.joint_state(name=["shoulder"], position=[msg.wrench.force.x])
        out.header.stamp = msg.header.stamp
        self.out.publish(out)

    def on_watchdog(self) -> None:
        now = self.get_clock().now().nanoseconds
        status = DiagnosticStatusData(OK, NAME, "relay", NAME, (("wrench", str(self.received)),))
        self.diag.publish(build_diagnostic_array(message_class, DiagnosticArraySample(now, "", (status,))))


def main(args: list[str] | None = None) -> int:
    sys.setswitchinterval(min(sys.getswitchinterval(), 0.0002))  # as bsp_identifier's main
    return run_node(
        NAME, RelayNode, __doc__.splitlines()[0], (Param(name="unused", default=0, description="no parameters"),), args
    )


if __name__ == "__main__":
    sys.exit(main(sys.argv))
