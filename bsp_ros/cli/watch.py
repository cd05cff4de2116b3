"""`bsp watch`: the live table of a running cell's estimate, over DDS (rclpy), in a terminal."""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from typing import Any

from bsp_ros.cli.argtypes import positive_float

__all__ = ["add_parser", "run"]

DESCRIPTION = (
    "Watch a running cell's estimate live, over ROS 2 (rclpy, DDS): the verdict and its cause in plain words, "
    "whether the session is precise enough (bsp_identifier's target_std_percent), each static moment and joint "
    "friction with its std and the largest term of its uncertainty, the weight support, and the inputs as the "
    "nodes take them (wrench, joint angles and marker frames per second, samples lost). Nothing on the cell "
    "changes. Runs until Ctrl-C (exit 130), --duration or --once. Exit code 0 if the last estimate shown is valid, "
    "1 if it is invalid, 3 if no estimate arrived, 6 if the middleware cannot start."
)
#: With --once: how long to gather the nodes' counters after the first estimate, so the rates are known, s
#: (joint_angle_estimator reports once a second).
SETTLE_S = 2.5


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp watch`."""
    parser = subparsers.add_parser(
        "watch", help="show a running cell's live estimate, verdict, precision and input rates", description=DESCRIPTION
    )
    parser.add_argument(
        "--domain", type=int, default=None, metavar="N", help="ROS domain id (default: $ROS_DOMAIN_ID, else 0)"
    )
    parser.add_argument(
        "--once",
        action="store_true",
        help="print one table once an estimate arrived (and the input rates are known) and exit",
    )
    parser.add_argument(
        "--duration", type=positive_float, default=None, metavar="S", help="stop after S seconds (default: Ctrl-C)"
    )
    parser.add_argument(
        "--timeout",
        type=positive_float,
        default=10.0,
        metavar="S",
        help="with --once: wait at most S seconds for an estimate (default 10)",
    )
    parser.add_argument(
        "--interval",
        type=positive_float,
        default=1.0,
        metavar="S",
        help="redraw every S seconds (default 1; a pipe gets one table per interval)",
    )
    parser.add_argument(
        "--topic-prefix",
        default="",
        metavar="NS",
        help="namespace of the cell's bsp topics, e.g. /cell2 for /cell2/bsp/estimate_json (default: none; "
        "/diagnostics is global)",
    )
    return parser


def _topic(prefix: str, name: str) -> str:
    return f"{prefix.rstrip('/')}/{name}" if prefix else name


def run(args: argparse.Namespace) -> int:
    """Subscribe, redraw the table until the end, and return the exit code of the last estimate shown."""
    from bsp_ros.cli.watch_view import WatchView
    from bsp_ros.errors import InputError
    from bsp_ros.live.runtime.qos import QosSpec
    from bsp_ros.live.runtime.ros import Client
    from msg_adapters.diagnostics import read_diagnostic_array

    if args.domain is not None and not 0 <= args.domain <= 232:
        raise InputError(f"--domain {args.domain}: a ROS domain id is 0-232")
    view = WatchView()
    client = Client(f"bsp_watch_{os.getpid()}", args.domain)
    domain = args.domain if args.domain is not None else int(os.environ.get("ROS_DOMAIN_ID", "0") or 0)

    def on_diagnostics(msg: Any) -> None:
        sample = read_diagnostic_array(msg)
        for status in sample.status:
            view.on_diagnostics(status.name, dict(status.values), sample.t_ns)

    def on_support(msg: Any) -> None:
        view.on_support((msg.wrench.force.y, msg.wrench.force.z, msg.wrench.torque.x))

    prefix = args.topic_prefix
    client.subscribe(
        "std_msgs/msg/String",
        _topic(prefix, "bsp/estimate_json"),
        lambda m: view.on_estimate(m.data, time.monotonic()),
        "estimates",
    )
    client.subscribe("diagnostic_msgs/msg/DiagnosticArray", "/diagnostics", on_diagnostics, "default")
    client.subscribe("geometry_msgs/msg/WrenchStamped", _topic(prefix, "bsp/weight_support"), on_support, "default")
    client.subscribe(
        "std_msgs/msg/Bool",
        _topic(prefix, "bsp/precision_reached"),
        lambda m: view.on_precision(bool(m.data)),
        QosSpec(reliable=True, depth=1, transient_local=True),  # latched, as bsp_identifier publishes it
    )
    try:
        _loop(client, view, args, domain)
    finally:
        client.close()
    return view.exit_code()


def _loop(client: Any, view: Any, args: argparse.Namespace, domain: int) -> None:
    """Spin and redraw until --duration, --once's table, or Ctrl-C (which main() turns into exit 130)."""
    interactive = sys.stdout.isatty()
    start = time.monotonic()
    end = start + args.duration if args.duration is not None else math.inf
    next_draw = start

    def draw(now: float) -> None:
        header = f"bsp watch: ROS domain {domain}, {now - start:.0f} s"
        table = view.render(now, header)
        print(("\033[2J\033[H" if interactive else "") + table + ("" if interactive else "\n"), flush=True)

    if args.once:
        client.spin_until(lambda: view.estimate is not None, min(args.timeout, end - start))
        if view.estimate is not None:
            client.spin(min(SETTLE_S, max(0.0, end - time.monotonic())))
        draw(time.monotonic())
        return
    while True:
        now = time.monotonic()
        if now >= end:
            break
        if now >= next_draw:
            draw(now)
            next_draw = now + args.interval
        client.spin(min(0.1, end - now))
    draw(time.monotonic())
