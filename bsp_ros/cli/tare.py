"""`bsp tare TARE --out FILE`: the F/T sensor's offset and the handle's load from a recording with the handle free."""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from bsp_ros.cli.identify import BAG_EXIT_CODES
from bsp_ros.errors import DataError, InputError, RuntimeBackendError

if TYPE_CHECKING:  # numpy is imported when a command runs, not on every `bsp` start
    import numpy as np

# Exit codes (README "Commands"): 0 tare written, 2 bad option value, 3 unusable recording (too short,
# NaN samples), 6 no middleware for --live, 10-16 the bag codes of `bsp identify`.
FIRST_MESSAGE_TIMEOUT_S = 10.0
# The defaults of docs/contract.md (a --cell file's names replace them where an option is left at its default).
WRENCH_TOPIC = "/ft_sensor/wrench"
WORLD_FRAME = "world"


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp tare`."""
    parser = subparsers.add_parser(
        "tare",
        help="estimate the F/T sensor offset and handle payload from a handle-free recording",
        description=(
            "Estimate the force/torque sensor's offset and the handle's load from a recording taken with the "
            "handle free (no arm attached; at least 5 s). The sensor's orientation comes from /tf_static and /tf, "
            "else the cell's TransformStamped topic, else the mounting the cell file (--cell) or the bag's metadata "
            "(`bsp record --cell`) states. If it varied enough, the handle's mass and centre of mass are separated "
            "from the offset; otherwise the constant load at the recorded orientation is estimated. Writes a YAML "
            "file (schema bsp_ros/core/tare/1) for `bsp identify BAG --tare FILE`. A recording whose load changed "
            "(an arm attached, the handle held) is refused unless --force. Exit codes: 0 written, 2 bad option, "
            "3 unusable recording, 6 no middleware (--live), 10-16 bag errors as for `bsp identify`."
        ),
    )
    parser.add_argument("bag", nargs="?", type=Path, metavar="TARE", help="tare recording (rosbag2 dir or .mcap)")
    parser.add_argument("--out", required=True, type=Path, metavar="FILE", help="tare file to write (YAML)")
    parser.add_argument(
        "--wrench-topic",
        default=WRENCH_TOPIC,
        metavar="TOPIC",
        help=f"wrench topic (default {WRENCH_TOPIC}, or the --cell file's)",
    )
    parser.add_argument("--tf-topic", default="/tf", metavar="TOPIC", help="tf topic (default /tf)")
    parser.add_argument(
        "--tf-static-topic", default="/tf_static", metavar="TOPIC", help="static tf topic (default /tf_static)"
    )
    parser.add_argument(
        "--world-frame",
        default=WORLD_FRAME,
        metavar="FRAME",
        help=f"frame of gravity, z up (default {WORLD_FRAME}, or the --cell file's)",
    )
    parser.add_argument(
        "--cell",
        dest="cell_file",
        type=Path,
        metavar="FILE",
        help="the cell description (bsp_ros/cell/1, as the nodes read it): its wrench topic, world frame and "
        "transform topic for the options left at their defaults, and its sensor mounting where the recording has "
        "no transform (default: the mounting `bsp record` wrote into the bag's metadata, if any)",
    )
    parser.add_argument("--live", action="store_true", help="record from the running wrench topic instead of a bag")
    parser.add_argument("--duration", type=float, metavar="S", help="--live: how long to record, s (>= 5)")
    parser.add_argument(
        "--force",
        action="store_true",
        help="write the tare even if the load changed during the recording (an arm attached, the handle held)",
    )
    return parser


def format_tare(tare: Any) -> str:
    """A few human-readable lines about a tare."""

    force, force_std = tare.force_offset_n
    torque, torque_std = tare.torque_offset_nm

    def vec(v: np.ndarray, s: np.ndarray, unit: str) -> str:
        return ", ".join(f"{a:.4g} +- {b:.2g}" for a, b in zip(v, s, strict=True)) + f" {unit}"

    what = "offset" if tare.load == "separated" else "constant load (offset and handle together)"
    lines = [
        f"tare of {tare.frame_id}: {tare.n_samples} samples over {tare.duration_s:.1f} s, "
        f"orientation swing {tare.swing_deg[0]:.1f}/{tare.swing_deg[1]:.1f} deg"
        + (f"; {tare.n_rejected} outlier samples left out" if tare.n_rejected else ""),
        f"force {what}: {vec(force, force_std, 'N')}",
        f"moment {what}: {vec(torque, torque_std, 'Nm')}",
    ]
    mass, com = tare.handle_mass_kg, tare.handle_com_m
    if mass is not None:
        lines.append(f"handle mass: {mass[0]:.4g} +- {mass[1]:.2g} kg")
        if com is not None:
            lines.append(f"handle COM: {vec(com[0], com[1], 'm')} (sensor frame, from the contact point)")
    else:
        lines.append(
            "the orientation did not vary enough (or is unknown): the constant load applies only at this "
            "orientation; swing the sensor to separate the handle"
        )
    return "\n".join(lines)


def collect_live_wrench(topic: str, duration_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    """Subscribe to a running WrenchStamped topic with rclpy for ``duration_s`` s from its first message.

    Returns
    -------
    t_ns (N,), force (N, 3) N, torque (N, 3) Nm, and the frame id.
    """
    import numpy as np

    try:
        import rclpy
        from geometry_msgs.msg import WrenchStamped
        from rclpy.qos import qos_profile_sensor_data
    except ImportError as error:
        raise RuntimeBackendError(f"bsp tare --live needs rclpy and geometry_msgs: {error}") from None
    rows: list[tuple[int, float, float, float, float, float, float]] = []
    frames: set[str] = set()

    def on_wrench(msg: Any) -> None:
        f, m = msg.wrench.force, msg.wrench.torque
        stamp = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
        rows.append((stamp, f.x, f.y, f.z, m.x, m.y, m.z))
        frames.add(msg.header.frame_id)

    rclpy.init()
    try:
        node = rclpy.create_node("bsp_tare")
        # Sensor-data QoS (best effort) matches reliable and best-effort publishers alike.
        node.create_subscription(WrenchStamped, topic, on_wrench, qos_profile_sensor_data)
        # The recording lasts duration_s from the first message (discovery can take a second or more).
        end = time.monotonic() + FIRST_MESSAGE_TIMEOUT_S
        first = False
        while time.monotonic() < end and rclpy.ok():
            rclpy.spin_once(node, timeout_sec=min(0.1, max(end - time.monotonic(), 0.0)))
            if rows and not first:
                first, end = True, time.monotonic() + duration_s
        node.destroy_node()
    finally:
        rclpy.try_shutdown()
    if not rows:
        raise DataError(f"no message on {topic} in {FIRST_MESSAGE_TIMEOUT_S:g} s: is the sensor driver running?")
    if len(frames) > 1:
        raise DataError(f"{topic} carried several frame ids {sorted(frames)}: one is expected")
    data = np.asarray(rows, dtype=np.float64)
    return np.asarray([r[0] for r in rows], dtype=np.int64), data[:, 1:4], data[:, 4:7], frames.pop()


def tare_topics(args: argparse.Namespace) -> Any:
    """The recording's topics and frames (:class:`bsp_ros.bag.TopicMap`) from the options; with ``--cell``, the
    cell's names for the options left at their defaults, its transform topic and the mounting it states."""
    from bsp_ros.bag import TopicMap
    from bsp_ros.bag.cell_metadata import topic_map_from_cell
    from bsp_ros.cell import read_cell_file

    cell = None if args.cell_file is None else topic_map_from_cell(read_cell_file(args.cell_file))
    wrench = args.wrench_topic if cell is None or args.wrench_topic != WRENCH_TOPIC else cell.wrench
    world = args.world_frame if cell is None or args.world_frame != WORLD_FRAME else cell.world_frame
    topics = TopicMap(
        wrench=wrench, markers={}, tf_static=args.tf_static_topic, tf=args.tf_topic, handle_pose="", world_frame=world
    )
    return topics if cell is None else replace(topics, transform=cell.transform, stated=cell.stated)


class _Recording(NamedTuple):
    """A tare recording's wrench (stamps ns, force N, torque Nm, sensor frame) and orientation (or None)."""

    t_ns: np.ndarray
    force_n: np.ndarray
    torque_nm: np.ndarray
    frame_id: str
    rotations: np.ndarray | None
    source: str
    orientation: str
    warnings: list[str]


#: How a tare's orientation source reads in its output (:data:`bsp_ros.bag.tare_reader.ORIENTATION_SOURCES`).
ORIENTATION_WORDS = {
    "tf": "/tf (turning)",
    "tf_static": "/tf_static",
    "topic": "the cell's TransformStamped topic",
    "cell": "the --cell file's mounting",
    "metadata": "the mounting in the bag's metadata",
    "world": "the wrench frame (world)",
    "unknown": "nowhere (unknown)",
}


def _live_recording(args: argparse.Namespace) -> _Recording:
    """``--live``: the running wrench topic for ``--duration`` s (its orientation unknown)."""
    from bsp_ros.core.tare import MIN_TARE_DURATION_S

    if args.bag is not None:
        raise InputError("give either a TARE recording or --live, not both")
    if args.duration is None:
        raise InputError(f"--live needs --duration S: how long to record, at least {MIN_TARE_DURATION_S:g} s")
    if not math.isfinite(args.duration) or args.duration < MIN_TARE_DURATION_S:
        raise InputError(f"--duration must be at least {MIN_TARE_DURATION_S:g} s, got {args.duration:g}")
    wrench_topic = tare_topics(args).wrench
    t_ns, force, torque, frame = collect_live_wrench(wrench_topic, args.duration)
    warning = "live tare: the sensor's orientation is not recorded, so the constant load is estimated"
    return _Recording(t_ns, force, torque, frame, None, f"live {wrench_topic}", "", [warning])


def _bag_recording(args: argparse.Namespace) -> _Recording:
    """A recorded tare bag, its orientation found as `bsp identify` finds a session's (BagError where unreadable)."""
    from bsp_ros.bag.tare_reader import read_tare_bag

    if args.bag is None:
        raise InputError("give a TARE recording (bag) or --live --duration S")
    if args.duration is not None:
        raise InputError("--duration applies to --live only")
    topics = tare_topics(args)
    read = read_tare_bag(args.bag, topics, topics.world_frame)
    source = read.orientation_source
    return _Recording(
        read.t_ns,
        read.force_n,
        read.torque_nm,
        read.frame_id,
        read.rotations_world_from_sensor,
        Path(args.bag).name,
        f"sensor orientation from {ORIENTATION_WORDS.get(source, source)}",
        list(read.warnings),
    )


def run(args: argparse.Namespace) -> int:
    """Estimate and write the tare; return the exit code."""
    from bsp_ros.bag.errors import BagError
    from bsp_ros.core.tare import MAX_UNSTEADINESS, estimate_tare, recording_warnings, write_tare_file

    out: Path = args.out
    if out.exists():
        raise InputError(f"{out} exists already: refusing to overwrite a tare (choose another --out)")
    try:
        recording = _live_recording(args) if args.live else _bag_recording(args)
    except BagError as error:
        print(f"bsp tare: error: {error}", file=sys.stderr)
        return BAG_EXIT_CODES.get(getattr(error, "code", ""), error.exit_code)
    t_ns, force, torque, frame, rotations, source, orientation, warnings = recording
    tare = estimate_tare(t_ns, force, torque, frame, rotations, source=source)
    if tare.unsteadiness > MAX_UNSTEADINESS and not args.force:
        # A tare taken with the arm attached would remove part of the arm's weight from every session it is
        # applied to, and the estimate would stay valid: refused here, before a file exists to be applied.
        raise DataError(
            f"the load changed during the recording (residual {tare.unsteadiness:.3g} x the sample-to-sample "
            f"noise, at most {MAX_UNSTEADINESS:g}): was an arm attached or the handle held? Record the tare again "
            "with the handle free (or --force to write it anyway)"
        )
    warnings += recording_warnings(tare)
    write_tare_file(out, tare)
    print(format_tare(tare))
    if orientation:
        print(orientation)
    for warning in warnings:
        print(f"warning: {warning}", file=sys.stderr)
    print(f"wrote {out}")
    return 0
