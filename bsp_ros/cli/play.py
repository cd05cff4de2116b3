"""`bsp play`: publish a bag's topics on ROS 2 (DDS) with the recorded timing."""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from bsp_ros.errors import InputError


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp play`."""
    parser = subparsers.add_parser(
        "play",
        help="publish a bag's topics on ROS 2 (DDS) with the recorded timing",
        description=(
            "Publish the messages of a rosbag2 MCAP bag on their topics (rclpy, serialized messages as recorded), "
            "timed by their receive times. Wrench and marker streams go out best effort (sensor_data), /tf_static "
            "transient-local and first, other topics reliable. A damaged bag plays its intact part and says what "
            "was lost. Where tf2_msgs is not installed, /tf_static and /tf go out as the cell's sensor rotation on "
            "its transform topic (geometry_msgs/TransformStamped, which bsp_identifier reads); another topic whose "
            "message package is not installed is skipped, by name. Exit codes: 0 played, 1 the bag was damaged or "
            "a topic the nodes need (wrench, markers, handle pose, the sensor's rotation) was dropped, 4 not a "
            "playable bag, 6 no rclpy."
        ),
    )
    parser.add_argument("bag", type=Path, metavar="BAG", help="bag directory, its metadata.yaml, or an .mcap file")
    parser.add_argument("--rate", type=float, default=1.0, metavar="R", help="time scale; 0 = as fast as possible")
    parser.add_argument("--fast", action="store_true", help="as fast as possible (same as --rate 0)")
    parser.add_argument("--loop", action="store_true", help="replay until interrupted (stamps jump back each pass)")
    parser.add_argument("--clock", action="store_true", help="publish the bag time on /clock")
    parser.add_argument("--clock-hz", type=float, default=40.0, metavar="HZ", help="/clock rate (default 40)")
    parser.add_argument("--topics", nargs="+", metavar="T", help="play only these topics")
    parser.add_argument("--domain", type=int, metavar="N", help="ROS domain id (default: ROS_DOMAIN_ID or 0)")
    parser.add_argument(
        "--wait-subscribers",
        type=float,
        default=2.0,
        metavar="S",
        help="wait up to S seconds for every topic to have a subscriber before playing (default 2)",
    )
    parser.add_argument(
        "--ack-timeout", type=float, default=5.0, metavar="S", help="wait for reliable acks at the end (default 5)"
    )
    parser.add_argument(
        "--cell",
        type=Path,
        metavar="FILE",
        help="the cell description (bsp_ros/cell/1): its frames and transform topic, and the topics the nodes need "
        "(default: the shipped bsp_ros/config/cell.yaml, as the nodes read it)",
    )
    return parser


@contextmanager
def stop_on_signals() -> Iterator[threading.Event]:
    """An event set by SIGINT/SIGTERM while the block runs (handlers restored afterwards)."""
    stop = threading.Event()
    previous: dict[int, Any] = {}

    def handler(signum: int, frame: Any) -> None:
        stop.set()

    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            previous[int(sig)] = signal.signal(sig, handler)
    try:
        yield stop
    finally:
        for number, old in previous.items():
            signal.signal(number, old)


def _announce(out: Callable[[str], None]) -> Callable[[Any], None]:
    def started(report: Any) -> None:
        unmatched = [t for t, n in report.matched.items() if n == 0]
        out(
            f"playing {len(report.published)} topics"
            + (f" ({len(unmatched)} without subscribers: {', '.join(sorted(unmatched))})" if unmatched else "")
        )

    return started


def run(args: argparse.Namespace) -> int:
    """Play the bag; return the exit code (0, or 1 if the bag was damaged or what the nodes need was dropped)."""
    from bsp_ros.cell import read_cell_file
    from bsp_ros.live.replay import play_bag
    from bsp_ros.live.replay.report import dropped_for_nodes

    if args.wait_subscribers < 0 or args.ack_timeout < 0:
        raise InputError("--wait-subscribers and --ack-timeout must be >= 0")
    cell = read_cell_file(args.cell)

    def say(line: str) -> None:
        print(line, flush=True)

    with stop_on_signals() as stop:
        report = play_bag(
            args.bag,
            rate=0.0 if args.fast else args.rate,
            loop=args.loop,
            clock=args.clock,
            clock_hz=args.clock_hz,
            topics=args.topics,
            domain_id=args.domain,
            wait_subscribers_s=args.wait_subscribers,
            ack_timeout_s=args.ack_timeout,
            stop=stop,
            on_start=_announce(say),
            cell=cell,
        )
    for line in report.summary_lines():
        say(line)
    total = sum(report.published.values())
    passes = f", {report.loops} complete passes" if args.loop else ""
    stopped = " (interrupted)" if report.interrupted else ""
    say(f"published {total} messages in {report.wall_s:.2f} s{passes}{stopped}")
    dropped = dropped_for_nodes(report, cell)
    if dropped:
        print(f"bsp play: warning: not played, though the nodes need it: {'; '.join(dropped)}", file=sys.stderr)
    if report.damaged:
        print("bsp play: warning: the bag is damaged; only its intact part was played", file=sys.stderr)
    return 1 if report.damaged or dropped else 0
