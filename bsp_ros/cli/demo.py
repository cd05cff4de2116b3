"""`bsp demo`: the simulated cell and the node suite on loopback, with a live table of estimates vs truth."""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from typing import TYPE_CHECKING, Any

from bsp_ros.cli.argtypes import float_within, positive_float
from bsp_ros.cli.live_table import estimate_rows, state_line, support_line

if TYPE_CHECKING:
    from bsp_ros.core.estimate_schema import Estimate

__all__ = [
    "add_parser",
    "introduction",
    "node_arguments",
    "render",
    "render_support",
    "run",
    "state_line",
    "verdict",
]

NODES = ("cell_simulator", "joint_angle_estimator", "bsp_identifier")
# bsp_identifier's default window (its `window_s` parameter), simulated seconds: until it has filled, or the
# first valid estimate, an invalid estimate is the expected warm-up, and the table says so.
WINDOW_S = 30.0
# The verdict: a valid final estimate whose static moments are within this of the simulated truth (%).
VERDICT_STATIC_PERCENT = 2.0
WIDTH = 110

DESCRIPTION = (
    "Run a simulated rehabilitation cell live: a robot slowly moving a relaxed arm (simulated, with a known "
    "truth), and the bsp_ros node suite identifying it, each a separate process talking ROS 2 (rclpy and its "
    "middleware, Fast DDS by default) on a private domain. A table shows each estimate beside the simulated "
    "truth as it converges, and the weight support the robot would apply; at the end a verdict says whether "
    "the estimate came out valid and close to the truth. Exit code 0 if it did, 1 if not, 6 if the "
    "middleware cannot start."
)


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp demo`."""
    parser = subparsers.add_parser(
        "demo", help="run the simulated cell and the nodes live, estimates vs truth", description=DESCRIPTION
    )
    parser.add_argument(
        "--duration", type=positive_float, default=60.0, metavar="S", help="wall-clock seconds to run (default 60)"
    )
    parser.add_argument(
        "--speed",
        type=float_within(0.01, 100.0),  # the cell_simulator's `speed` parameter range
        default=2.0,
        metavar="X",
        help="simulated seconds per wall second, 0.01-100 (default 2)",
    )
    parser.add_argument(
        "--subject",
        choices=("human", "paper-arm"),
        default="human",
        help="human: a 3-segment arm (upper arm, forearm, hand) with de Leva table values; paper-arm: the method "
        "paper's 2-segment mechanical arm (default human)",
    )
    parser.add_argument(
        "--mode",
        choices=("windowed", "recursive"),
        default="windowed",
        help="windowed: the batch estimator over a sliding 30 s window, 5 updates/s; recursive: recursive least "
        "squares on every joint state (default windowed)",
    )
    parser.add_argument(
        "--support-fraction",
        type=float_within(0.0, 1.0),
        default=0.5,
        metavar="S",
        help="share of the arm's gravity torques bsp/weight_support asks the robot to carry, 0-1 (default 0.5)",
    )
    parser.add_argument(
        "--seed",
        type=int,
        default=0,
        metavar="N",
        help="seed of the simulated noise; the same seed gives the same session",
    )
    parser.add_argument(
        "--domain", type=int, default=None, metavar="ID", help="ROS domain id (default: derived from the pid, 2..101)"
    )
    return parser


def _rows(estimate: Estimate, truth: dict[str, Any]) -> list[tuple[str, float | None, float | None, float | None]]:
    return [
        (f"{owner} {key}", q.value, q.std, truth.get(group, {}).get(owner, {}).get(key))
        for group, owner, key, q in estimate_rows(estimate)
    ]


def render(estimate: Estimate | None, truth: dict[str, Any], elapsed_s: float, warming_up: bool = False) -> str:
    """The live table: each identifiable parameter, its estimate +- std, the truth and the error."""
    if estimate is None:
        return f"t={elapsed_s:5.1f} s  waiting for the first estimate (the nodes are starting)..."
    lines = [
        f"t={elapsed_s:5.1f} s  {state_line(estimate, warming_up)}",
        f"{'parameter':28s} {'estimate':>10s} {'+- std':>9s} {'truth':>9s} {'error %':>8s}",
    ]
    for name, value, std, true in _rows(estimate, truth):
        if value is None:
            continue
        error = "" if not true else f"{100 * (value - true) / true:+8.2f}"
        lines.append(
            f"{name:28s} {value:10.4f} {std or 0:9.2g} {true if true is not None else float('nan'):9.4f} {error}"
        )
    return "\n".join(lines)


def render_support(msg: Any, support_fraction: float) -> str:
    """One line: the latest bsp/weight_support wrench, or that none is published (no valid estimate yet)."""
    wrench = None if msg is None else (msg.wrench.force.y, msg.wrench.force.z, msg.wrench.torque.x)
    return support_line(wrench, support_fraction)


def introduction(args: argparse.Namespace, middleware: str, domain: int) -> str:
    """What runs, said once before the table."""
    arm = (
        "a relaxed 3-segment human arm (de Leva table, 75 kg, 1.78 m)"
        if args.subject == "human"
        else "the method paper's 2-segment mechanical arm (Table 1)"
    )
    share = 100 * args.support_fraction
    mode = f"over a sliding {WINDOW_S:g} s window, 5 times/s" if args.mode == "windowed" else "recursively"
    head = (
        f"bsp demo: a simulated rehabilitation cell, live for {args.duration:g} s at {args.speed:g}x real time, on "
        f"ROS 2 (rclpy, {middleware}, private domain {domain}). Three node processes run:"
    )
    tail = (
        "This console compares each estimate with the simulated truth. The first estimates are invalid while the "
        "window fills and every joint has yet to move both ways: that warm-up is expected. The weight support "
        "changes as the robot moves the arm: it is a share of gravity at the current posture."
    )
    return "\n".join(
        [
            textwrap.fill(head, WIDTH),
            f"  cell_simulator         a robot moving {arm} slowly;",
            f"{'':25s}publishes the handle's force/torque wrench, four motion-capture markers, the truth",
            "  joint_angle_estimator  the joint angles from the markers",
            f"  bsp_identifier         the static moments and passive joint moments, {mode};",
            f"{'':25s}and the weight support: what the robot would apply to carry {share:g} % of the arm's weight",
            "Each reads the cell description bsp_ros/config/cell.yaml (the simulated cell's frames, topics and force "
            "sensor",
            "mounting), as the nodes of a real cell read theirs.",
            textwrap.fill(tail, WIDTH),
            "",
        ]
    )


def verdict(estimate: Estimate | None, truth: dict[str, Any]) -> tuple[bool, str]:
    """Whether the demo worked (a valid final estimate, static moments near the truth), and what it showed."""
    if estimate is None:
        return False, (
            "verdict: FAILED - no estimate arrived. The nodes did not reach each other over the middleware; "
            "see the messages above (a firewall or a ROS_LOCALHOST_ONLY setting can block discovery)."
        )
    if not estimate.valid:
        return False, (
            f"verdict: FAILED - the last estimate is invalid: {estimate.quality.message}. "
            "Run longer (--duration) if it was still warming up."
        )
    errors = [(name, 100 * (value - true) / true) for name, value, _, true in _rows(estimate, truth) if value and true]
    static = [(name.split()[0], error) for name, error in errors if "static_moment" in name]
    friction = [(name.split()[0], error) for name, error in errors if "coulomb" in name]
    worst_name, worst = max(static, key=lambda item: abs(item[1])) if static else ("", 0.0)
    meaning = (
        "What the numbers mean: a static moment (kg m) is the mass times the distance of its centre of mass from "
        "the joint, summed over the segments beyond it: how hard gravity pulls the arm about that joint, what a "
        "robot must carry. Coulomb (Nm) is the joint's dry friction, the passive moment that resists motion. "
        "std is the estimator's own uncertainty; error % is against the simulated truth."
    )
    if not static:
        return False, "verdict: FAILED - no simulated truth arrived (sim/truth) to compare the estimate with."
    if abs(worst) > VERDICT_STATIC_PERCENT:
        return False, (
            f"verdict: FAILED - the estimate is valid but the {worst_name}'s static moment is {worst:+.2f} % "
            f"off the truth (more than {VERDICT_STATIC_PERCENT:g} %).\n" + meaning
        )
    friction_text = f", every Coulomb friction within {max(abs(e) for _, e in friction):.2g} %" if friction else ""
    return True, (
        f"verdict: OK - the final estimate is valid; every static moment is within {abs(worst):.2g} % of the "
        f"simulated truth (largest: {worst_name}){friction_text}. On a real cell the same nodes take the sensor's "
        "and the motion capture's topics instead of the simulator's (docs/cell-guide.md).\n" + meaning
    )


def node_arguments(args: argparse.Namespace) -> dict[str, list[str]]:
    """Each node's ``--ros-args``: the demo's options, and the cell description every node reads as on a real cell.

    The shipped cell file describes the simulated cell: the simulator mounts its sensor and publishes its
    transform as the file says, and the identifier takes the rotation from that transform (from the file's mounting
    where none comes), so the demo runs the path a real cell runs, with or without tf2_msgs.
    """
    from bsp_ros.cell import SHIPPED_CELL

    n_segments = "3" if args.subject == "human" else "2"
    cell = ["-p", f"cell_file:={SHIPPED_CELL}"]
    return {
        "cell_simulator": [
            *cell,
            *("-p", f"speed:={args.speed}", "-p", f"subject:={args.subject}", "-p", f"seed:={args.seed}"),
            *("-p", "wait_for_subscribers:=1"),  # the session starts once the identifier takes the wrench
        ],
        "joint_angle_estimator": [*cell, "-p", f"n_segments:={n_segments}"],
        "bsp_identifier": [
            *cell,
            *("-p", f"n_segments:={n_segments}", "-p", f"mode:={args.mode}"),
            *("-p", f"support_fraction:={float(args.support_fraction)}"),
        ],
    }


def run(args: argparse.Namespace) -> int:
    """Start the nodes, watch the estimates converge, print the final errors."""
    from bsp_ros.core.estimate_schema import Estimate
    from bsp_ros.live.runtime.ros import Client

    # 1..101: the ROS 2 domain ids safe on Linux; 0 (everyone's default) is left alone.
    domain = args.domain if args.domain is not None else 2 + os.getpid() % 100
    env = {**os.environ, "ROS_DOMAIN_ID": str(domain)}
    node_args = node_arguments(args)
    client = Client("bsp_demo_console", domain)
    print(introduction(args, _middleware(), domain), flush=True)
    latest: dict[str, Any] = {}
    truth: dict[str, Any] = {}
    client.subscribe(
        "std_msgs/msg/String",
        "bsp/estimate_json",
        lambda m: latest.__setitem__("estimate", Estimate.from_json(json.loads(m.data))),
        "estimates",
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
    seen_valid = False
    first_estimate_s: float | None = None
    start = time.monotonic()
    try:
        while time.monotonic() - start < args.duration:
            client.spin(1.0 if interactive else 5.0)
            if any(p.poll() is not None for p in processes):
                failed = [n for n, p in zip(NODES, processes, strict=True) if p.poll() is not None]
                print(f"bsp demo: node(s) {failed} stopped", file=sys.stderr)
                break
            elapsed_s = time.monotonic() - start
            estimate = latest.get("estimate")
            if estimate is not None and first_estimate_s is None:
                first_estimate_s = elapsed_s  # the nodes take seconds to start and to discover each other
            if estimate is not None and estimate.valid:
                seen_valid = True
            since_first_s = 0.0 if first_estimate_s is None else elapsed_s - first_estimate_s
            warming_up = not seen_valid and since_first_s * args.speed < WINDOW_S + 10.0
            table = render(estimate, truth, elapsed_s, warming_up)
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
    estimate = latest.get("estimate")
    print("\nfinal estimate (truth beside it):")
    print(render(estimate, truth, time.monotonic() - start))
    print(render_support(latest.get("support"), args.support_fraction))
    worked, text = verdict(estimate, truth)
    print("\n" + "\n\n".join(textwrap.fill(part, WIDTH) for part in text.split("\n")))
    return 0 if worked else 1


def _middleware() -> str:
    """The rmw implementation rclpy runs on (Fast DDS as `rmw_fastrtps_cpp` by default on Jazzy)."""
    try:
        from rclpy.utilities import get_rmw_implementation_identifier

        return str(get_rmw_implementation_identifier())
    except Exception:  # an rclpy without it: the environment's choice, or Jazzy's default
        return os.environ.get("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
