"""`bsp demo`: the simulated cell and the node suite on loopback, with a live table of estimates vs truth."""

from __future__ import annotations

import argparse
import json
import os
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
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--domain", type=int, default=None, help="DDS domain id (default: derived from the pid)")
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


def run(args: argparse.Namespace) -> int:
    """Start the nodes, watch the estimates converge, print the final errors."""
    from bsp_ros.runtime import make_context

    domain = args.domain if args.domain is not None else 100 + os.getpid() % 100
    env = {**os.environ, "BSP_ROS_BACKEND": "dds", "ROS_DOMAIN_ID": str(domain)}
    n_segments = "3" if args.subject == "human" else "2"
    node_args = {
        "cell_simulator": [
            "--param",
            f"speed:={args.speed}",
            "--param",
            f"subject:={args.subject}",
            "--param",
            f"seed:={args.seed}",
        ],
        "joint_angle_estimator": ["--param", f"n_segments:={n_segments}"],
        "bsp_identifier": ["--param", f"n_segments:={n_segments}", "--param", f"mode:={args.mode}"],
    }
    context = make_context("dds", domain_id=domain, args=[])
    node = context.create_node("bsp_demo_console")
    latest: dict[str, Any] = {}
    truth: dict[str, Any] = {}
    node.create_subscription(
        "std_msgs/msg/String", "bsp/estimate_json", lambda m: latest.__setitem__("doc", json.loads(m.data)), "estimates"
    )
    node.create_subscription(
        "std_msgs/msg/String", "sim/truth", lambda m: truth.update(json.loads(m.data)), "tf_static_listener"
    )
    processes = [
        subprocess.Popen(
            [sys.executable, "-m", f"bsp_ros.nodes.{name}", *node_args[name]],
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
            context.spin(1.0 if interactive else 5.0)
            if any(p.poll() is not None for p in processes):
                failed = [n for n, p in zip(NODES, processes, strict=True) if p.poll() is not None]
                print(f"bsp demo: node(s) {failed} stopped", file=sys.stderr)
                break
            table = render(latest.get("doc"), truth, time.monotonic() - start)
            print(("\033[2J\033[H" if interactive else "") + table + ("" if interactive else "\n"), flush=True)
    finally:
        for process in processes:
            process.terminate()
        for process in processes:
            try:
                process.wait(5)
            except subprocess.TimeoutExpired:
                process.kill()
        context.shutdown()
    document = latest.get("doc")
    print("\nfinal estimate (truth beside it):")
    print(render(document, truth, time.monotonic() - start))
    return 0 if document is not None and document["quality"]["valid"] else 1
