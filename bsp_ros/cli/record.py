"""`bsp record`: record ROS 2 topics from DDS into a rosbag2 MCAP bag that survives being killed."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from bsp_ros.cli.argtypes import positive_float
from bsp_ros.cli.play import stop_on_signals


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp record`."""
    parser = subparsers.add_parser(
        "record",
        help="record ROS 2 topics (DDS) into a rosbag2 MCAP bag",
        description=(
            "Subscribe to ROS 2 topics (rclpy, serialized messages) and write a rosbag2 bag (metadata.yaml "
            "version 9 and one .mcap with small CRC-checked chunks, flushed every 0.25 s, so a killed recorder "
            "loses well under a second). Types come from the publishers or from TOPIC:TYPE (a type whose message "
            "package is not installed is refused). Each topic's metadata.yaml entry and MCAP channel list the same "
            "QoS profiles, those its publishers offered when its first message arrived, as rosbag2 records them. "
            "Stop with Ctrl-C/SIGTERM or --duration. Exit codes: 0 recorded, 2 bad argument "
            "(topic or type name, a type not installed), 3 nothing recorded (no message arrived: no bag is left), "
            "4 the bag exists, 6 no rclpy. Never name the bag after a person."
        ),
    )
    parser.add_argument("topics", nargs="+", metavar="TOPIC", help="topic, or TOPIC:pkg/msg/Type")
    parser.add_argument("--out", "-o", required=True, type=Path, metavar="DIR", help="bag directory to create")
    parser.add_argument("--domain", type=int, metavar="N", help="ROS domain id (default: ROS_DOMAIN_ID or 0)")
    parser.add_argument("--duration", type=positive_float, metavar="S", help="stop after S seconds")
    parser.add_argument("--chunk-kib", type=int, default=48, metavar="KIB", help="MCAP chunk size (default 48)")
    parser.add_argument(
        "--flush-interval", type=float, default=0.25, metavar="S", help="longest time data stays unwritten"
    )
    return parser


def run(args: argparse.Namespace) -> int:
    """Record until stopped; return the exit code."""
    from bsp_ros.live.recorder import parse_topic_specs, record
    from bsp_ros.validation import check_output_dir

    check_output_dir("--out", args.out)  # a clear error before subscribing (the recorder refuses an existing bag)
    specs = parse_topic_specs(args.topics)

    def subscribed(topic: str, msgtype: str) -> None:
        print(f"subscribed {topic} [{msgtype}]", flush=True)

    print(f"recording {len(specs)} topic{'' if len(specs) == 1 else 's'} into {args.out}", flush=True)
    with stop_on_signals() as stop:
        report = record(
            specs,
            args.out,
            domain_id=args.domain,
            duration_s=args.duration,
            chunk_bytes=args.chunk_kib * 1024,
            flush_interval_s=args.flush_interval,
            stop=stop,
            on_subscribe=subscribed,
        )
    for line in report.summary_lines():
        print(line, flush=True)
    print(f"wrote {report.path} ({sum(report.counts.values())} messages, {report.wall_s:.2f} s)", flush=True)
    return 0
