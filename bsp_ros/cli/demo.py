"""`bsp demo`: the simulated cell and the node suite on loopback, with a live table of estimates vs truth."""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from typing import Any

from bsp_ros.cli.argtypes import float_within, positive_float

NODES = ("cell_simulator", "joint_angle_estimator", "bsp_identifier")


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp demo`."""
    parser = subparsers.add_parser("demo", help="run the simulated cell and the nodes live, estimates vs truth")
    parser.add_argument("--duration", type=positive_float, default=60.0, help="wall-clock seconds to run (default 60)")
    parser.add_argument(
        "--speed",
        type=float_within(0.01, 100.0),  # the cell_simulator's `speed` parameter range
        default=2.0,
        help="simulated seconds per wall second, 0.01-100 (default 2)",
    )
    parser.add_argument("--subject", choices=("human", "paper-arm"), default="human")
    parser.add_argument("--mode", choices=("windowed", "recursive"), default="windowed")
    parser.add_argument(
        "--support-fraction",
        type=float_within(0.0, 1.0),
        default=0.5,
        help="share of the arm's gravity torques bsp/weight_support asks the robot to carry, 0-1 (default 0.5)",
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument(
        "--domain", type=int, default=None, help="ROS domain id (default: derived from the pid, 2..101)"
    )
    return parser


def _rows(
    document: dict[str, Any], truth: dict[str, Any]
) -> list[tuple[str, float | None, float | None, float | None]]:
    rows = []
    for group, key in (("segments", "static_moment_kgm"), ("joints", "coulomb_nm")):
        for owner, quantities in document.get(group, {}).items():
            q = quantities.get(key, {})
            true = truth.get(group, {}).get(owner, {}).get(key)
            rows.append((f"{owner} {key}", q.get("value"), q.get("std"), true))
    return rows


def render(document: dict[str, Any] | None, truth: dict[str, Any], elapsed_s: float) -> str:
    """The live table: each identifiable parameter, its estimate +- std, the truth and the error."""
    if document is None:
        return f"t={elapsed_s:5.1f} s  waiting for the first estimate..."
    quality = document["quality"]
    lines = [
        f"t={elapsed_s:5.1f} s  {'VALID' if quality['valid'] else 'invalid'}: {quality.get('message', '')}",
        f"{'parameter':28s} {'estimate':>10s} {'+- std':>9s} {'truth':>9s} {'error %':>8s}",
    ]
    for name, value, std, true in _rows(document, truth):
        if value is None:
            continue
        error = "" if not true else f"{100 * (value - true) / true:+8.2f}"
        lines.append(
            f"{name:28s} {value:10.4f} {std or 0:9.2g} {true if true is not None else float('nan'):9.4f} {error}"
        )
    return "\n".join(lines)


def render_support(msg: Any, support_fraction: float) -> str:
    """One line: the latest bsp/weight_support wrench, or that none is published (no valid estimate yet)."""
    if msg is None:
        return f"weight support ({support_fraction:g} of the arm's gravity torques): none yet (no valid estimate)"
    force, torque = msg.wrench.force, msg.wrench.torque
    return (
        f"weight support ({support_fraction:g} of the arm's gravity torques), on the hand in world: "
        f"F_y {force.y:+.2f} N, F_z {force.z:+.2f} N, M_x {torque.x:+.3f} Nm"
    )


def run(args: argparse.Namespace) -> int:
    """Start the nodes, watch the estimates converge, print the final errors."""
    from bsp_ros.live.runtime.ros import Client, has_message

    # 1..101: the ROS 2 domain ids safe on Linux; 0 (everyone's default) is left alone.
    domain = args.domain if args.domain is not None else 2 + os.getpid() % 100
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain)}
    n_segments = "3" if args.subject == "human" else "2"
    identifier = ["-p", f"n_segments:={n_segments}", "-p", f"mode:={args.mode}"]
    identifier += ["-p", f"support_fraction:={float(args.support_fraction)}"]
    if not has_message("tf2_msgs/msg/TFMessage"):
        # No /tf_static without tf2_msgs: the identifier gets the simulated sensor's rotation as a parameter.
        from bsp_ros.core.simulation import human_arm_cell, paper_mechanical_arm_cell
        from msg_adapters.rotation import quaternion_from_matrix

        spec = human_arm_cell() if args.subject == "human" else paper_mechanical_arm_cell()
        xyzw = quaternion_from_matrix(spec.sensor.rotation_world_from_sensor)
        identifier += ["-p", "wrench_frame_rotation_xyzw:=[" + ", ".join(repr(float(v)) for v in xyzw) + "]"]
    node_args = {
        "cell_simulator": ["-p", f"speed:={args.speed}", "-p", f"subject:={args.subject}", "-p", f"seed:={args.seed}"],
        "joint_angle_estimator": ["-p", f"n_segments:={n_segments}"],
        "bsp_identifier": identifier,
    }
    client = Client("bsp_demo_console", domain)
    latest: dict[str, Any] = {}
    truth: dict[str, Any] = {}
    client.subscribe(
        "std_msgs/msg/String", "bsp/estimate_json", lambda m: latest.__setitem__("doc", json.loads(m.data)), "estimates"
    )
    client.subscribe(
        "std_msgs/msg/String", "sim/truth", lambda m: truth.update(json.loads(m.data)), "tf_static_listener"
    )
    client.subscribe(
        "geometry_msgs/msg/WrenchStamped", "bsp/weight_support", lambda m: latest.__setitem__("support", m)
    )
    processes = [
        subprocess.Popen(
            [sys.executable, "-m", f"bsp_ros.live.nodes.{name}", "--ros-args", *node_args[name]],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        for name in NODES
    ]
    interactive = sys.stdout.isatty()
    start = time.monotonic()
    try:
        while time.monotonic() - start < args.duration:
            client.spin(1.0 if interactive else 5.0)
            if any(p.poll() is not None for p in processes):
                failed = [n for n, p in zip(NODES, processes, strict=True) if p.poll() is not None]
                print(f"bsp demo: node(s) {failed} stopped", file=sys.stderr)
                break
            table = render(latest.get("doc"), truth, time.monotonic() - start)
            table += "\n" + render_support(latest.get("support"), args.support_fraction)
            print(("\033[2J\033[H" if interactive else "") + table + ("" if interactive else "\n"), flush=True)
    finally:
        for process in processes:
            process.send_signal(signal.SIGINT)  # the nodes' clean exit (rclpy's handler); SIGKILL if it hangs
        for process in processes:
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(5)
        client.close()
    document = latest.get("doc")
    print("\nfinal estimate (truth beside it):")
    print(render(document, truth, time.monotonic() - start))
    print(render_support(latest.get("support"), args.support_fraction))
    return 0 if document is not None and document["quality"]["valid"] else 1
