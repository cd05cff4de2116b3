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
            "The cell file's sensor mounting (frames and rotation) goes into metadata.yaml's custom_data, where "
            "`bsp identify` finds it if the bag records no transform; one line names the file (and says so where it "
            "is the shipped simulated cell's, whose mounting is the simulator's); where tf2_msgs is not installed, "
            "/tf_static "
            "and /tf give way to the cell's transform topic (geometry_msgs/TransformStamped). "
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
    parser.add_argument(
        "--cell",
        type=Path,
        metavar="FILE",
        help="the cell description (bsp_ros/cell/1) whose sensor mounting and transform topic go with the bag "
        "(default: the shipped bsp_ros/config/cell.yaml, as the nodes read it)",
    )
    return parser


def run(args: argparse.Namespace) -> int:
    """Record until stopped; return the exit code."""
    from bsp_ros.bag.cell_metadata import cell_file_said, custom_data_from_cell
    from bsp_ros.cell import read_cell_file
    from bsp_ros.live.recorder import parse_topic_specs, record, transform_topic_for_tf
    from bsp_ros.live.runtime.ros import has_message
    from bsp_ros.validation import check_output_dir

    check_output_dir("--out", args.out)  # a clear error before subscribing (the recorder refuses an existing bag)
    cell = read_cell_file(args.cell)
    # Which cell's mounting goes into metadata.yaml: `bsp identify` takes it where the bag records no transform.
    rotation = [round(float(v), 6) for v in cell.rotation_xyzw]
    mounting = f"sensor {cell.sensor_frame} in {cell.world_frame}, rotation xyzw {rotation}"
    print(f"cell: {mounting} from {cell_file_said(cell)}", flush=True)
    tf_installed = has_message("tf2_msgs/msg/TFMessage")
    specs, note = transform_topic_for_tf(parse_topic_specs(args.topics), cell.transform_topic, tf_installed)
    if note:
        print(f"note: {note}", flush=True)

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
            custom_data=custom_data_from_cell(cell),
        )
    for line in report.summary_lines():
        print(line, flush=True)
    print(f"wrote {report.path} ({sum(report.counts.values())} messages, {report.wall_s:.2f} s)", flush=True)
    return 0
