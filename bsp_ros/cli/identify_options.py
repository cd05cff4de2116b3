"""The options of `bsp identify` (method, passive model, body data, topics, tare), shared with `bsp sessions add`."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from bsp_ros.cli.argtypes import float_within, positive_float
from bsp_ros.core.sensor_zero import ZERO_SD_N, ZERO_SD_NM
from bsp_ros.errors import InputError

# bsp_ros.core.pipeline.METHODS, spelled out here so the parser needs no scipy.
METHODS = ("joint", "paper")
SEXES = ("male", "female")


def add_identify_arguments(parser: argparse.ArgumentParser | Any) -> None:
    """Register the identification options on ``parser`` (a parser or an argument group)."""
    parser.add_argument("--method", choices=METHODS, default="joint", help="joint (ours, default) or paper")
    parser.add_argument(
        "--passive",
        default=None,
        metavar="MODEL",
        help="passive model: terms joined by + out of coulomb, viscous, offset, stiffness, nonlinear, coupling, higher "
        "(e.g. coulomb+offset+stiffness), or auto: the data choose the elastic terms and the std holds the spread "
        "of the models they cannot reject. Default: coulomb, and auto where the data show an elastic passive "
        "moment (a model given here is kept: such data then make the estimate invalid)",
    )
    parser.add_argument(
        "--body-mass", type=positive_float, metavar="KG", help="body mass for the anthropometric prior, kg"
    )
    parser.add_argument("--height", type=positive_float, metavar="M", help="body height for the prior, m")
    parser.add_argument(
        "--sex", choices=SEXES, default=None, help="anthropometric table (default: the subject record's, else male)"
    )
    parser.add_argument("--wrench-topic", default="/ft_sensor/wrench")
    parser.add_argument(
        "--marker-topic",
        action="append",
        default=[],
        metavar="NAME=TOPIC",
        help="remap a marker topic, e.g. elbow=/vicon/elbow (repeatable)",
    )
    parser.add_argument("--tf-topic", default="/tf")
    parser.add_argument("--tf-static-topic", default="/tf_static")
    parser.add_argument(
        "--handle-pose-topic",
        default="/robot/handle_pose",
        metavar="TOPIC",
        help="the robot's PoseStamped of the contact point in world: where the bag has it, it stands for the hand "
        "marker ('' to use the marker) (default: /robot/handle_pose)",
    )
    parser.add_argument(
        "--emg-topic",
        default="/emg/envelope",
        metavar="TOPIC",
        help="the muscles' EMG envelopes (std_msgs/Float32MultiArray): where the bag has them, the stretches they "
        "show active are left out beside the torque's ('' to ignore them) (default: /emg/envelope)",
    )
    add_placement_arguments(parser)
    parser.add_argument(
        "--tare",
        type=Path,
        metavar="FILE",
        help="tare file of `bsp tare`: remove the sensor offset and handle load; its std joins the estimate's",
    )
    add_zero_arguments(parser)
    cell_help = (
        "the cell description (bsp_ros/cell/1, as the nodes read it): its topics, for options left at their "
        "defaults; its tare, without --tare; and its sensor mounting, where the bag records no rotation "
        "(default: the bag's own, /tf_static, /tf, the transform topic, or what `bsp record` wrote)"
    )
    try:
        parser.add_argument("--cell", dest="cell_file", type=Path, metavar="FILE", help=cell_help)
    except argparse.ArgumentError:  # `bsp sessions add` has --cell NAME already (the cell's name in the store)
        parser.add_argument("--cell-file", dest="cell_file", type=Path, metavar="FILE", help=cell_help)
    parser.add_argument(
        "--wrench-delay-s",
        type=float_within(-10.0, 10.0),
        metavar="S",
        help="delay of the wrench stamps behind the marker stamps the cell knows (s; a wrench stamped t was "
        "measured at t - S): compensated as given (default: estimated from the data, compensated when resolved)",
    )


def add_placement_arguments(parser: argparse.ArgumentParser | Any) -> None:
    """``--marker-placement-sd-mm`` and ``--handle-pose-sd-mm``: the placement terms of every std (`bsp identify`,
    and `bsp plan`, which predicts them)."""
    parser.add_argument(
        "--marker-placement-sd-mm",
        type=float_within(0.0, 50.0),
        default=2.0,
        metavar="MM",
        help="how far (1 sd per in-plane axis) a skin marker may sit from its joint centre: its effect is the "
        "marker_placement term of every std (0 for markers known to sit on the centres) (default: 2)",
    )
    parser.add_argument(
        "--handle-pose-sd-mm",
        type=float_within(0.0, 50.0),
        default=0.5,
        metavar="MM",
        help="how far (1 sd per axis) the robot's contact point may sit from the motion capture's: its registration "
        "to world; in the std like a skin marker's placement (2 mm) (default: 0.5)",
    )


def add_zero_arguments(parser: argparse.ArgumentParser | Any) -> None:
    """``--zero-sd-n`` and ``--zero-sd-nm``: an untared sensor's zero, in every std (`bsp identify`, `bsp plan`)."""
    parser.add_argument(
        "--zero-sd-n",
        type=float_within(0.0, 100.0),
        default=ZERO_SD_N,
        metavar="N",
        help="without --tare, how far (1 sd per sensor axis) the sensor's zero may be off: the data cannot tell a "
        "force offset from arm weight, so it is in the std (e.g. 0.2 for a sensor zeroed with the handle on just "
        f"before the arm was strapped in) (default: {ZERO_SD_N:g})",
    )
    parser.add_argument(
        "--zero-sd-nm",
        type=float_within(0.0, 10.0),
        default=ZERO_SD_NM,
        metavar="NM",
        help=f"the same for the sensor's moment zero, N m (default: {ZERO_SD_NM:g})",
    )


def looks_like_bag(path: Path) -> bool:
    """Whether ``path`` is a recording (a rosbag2 directory or an .mcap file) rather than a tare file."""
    if path.is_dir():
        return (path / "metadata.yaml").is_file() or any(path.glob("*.mcap"))
    return path.suffix == ".mcap"


def read_tare(path: Path | None) -> Any:
    """The tare file given as ``--tare``, or an InputError naming the file and, for a recording, how to make one."""
    if path is None:
        return None
    from bsp_ros.core.tare import read_tare_file

    if looks_like_bag(path):
        raise InputError(
            f"--tare {path} is a recording (a bag), not a tare file: make the file with "
            f"`bsp tare {path} --out FILE`, then give --tare FILE"
        )
    if path.is_dir():
        raise InputError(f"--tare {path} is a directory, not a tare file (`bsp tare TARE_BAG --out FILE` makes one)")
    if not path.exists():
        raise InputError(f"--tare {path}: no such file (`bsp tare TARE_BAG --out FILE` makes one)")
    try:
        return read_tare_file(path)
    except InputError as error:
        raise InputError(f"--tare {path}: {error}") from None


def cell_from_args(args: argparse.Namespace) -> Any:
    """The cell description of ``--cell`` (``--cell-file`` for `bsp sessions add`:
    :class:`bsp_ros.cell.CellDescription`), or None without it."""
    from bsp_ros.cell import read_cell_file

    path = getattr(args, "cell_file", None)
    return None if path is None else read_cell_file(path)


def tare_path(args: argparse.Namespace) -> Path | None:
    """The tare file: ``--tare``, else the ``--cell`` file's, else None."""
    cell = cell_from_args(args) if args.tare is None else None
    return args.tare if cell is None else cell.tare_file


def topics_from_args(args: argparse.Namespace) -> Any:
    """The bag's topic names (:class:`bsp_ros.bag.TopicMap`) from ``--wrench-topic``, ``--marker-topic``, ...;
    with ``--cell``, the cell's names for the options left at their defaults, and the mounting it states."""
    from dataclasses import replace

    from bsp_ros.bag import TopicMap
    from bsp_ros.bag.cell_metadata import topic_map_from_cell

    cell = cell_from_args(args)
    default = TopicMap()
    base = default if cell is None else topic_map_from_cell(cell)
    # An option left at its default takes the cell's name.
    wrench = base.wrench if args.wrench_topic == default.wrench else args.wrench_topic
    handle_pose = base.handle_pose if args.handle_pose_topic == default.handle_pose else args.handle_pose_topic
    markers = dict(base.markers)
    for item in args.marker_topic:
        name, _, topic = item.partition("=")
        if name not in markers or not topic:
            raise InputError(f"--marker-topic takes NAME=TOPIC with NAME in {sorted(markers)}, got {item!r}")
        if topic in (wrench, args.tf_topic, args.tf_static_topic, handle_pose):
            raise InputError(f"--marker-topic {item}: {topic} is already the wrench, a tf or the handle pose topic")
        markers[name] = topic
    emg = base.emg if args.emg_topic == default.emg else args.emg_topic
    topics = TopicMap(
        wrench=wrench,
        markers=markers,
        tf_static=args.tf_static_topic,
        tf=args.tf_topic,
        handle_pose=handle_pose,
        emg=emg,
    )
    return replace(topics, transform=base.transform, stated=base.stated, world_frame=base.world_frame)


def options_from_args(args: argparse.Namespace, body: dict[str, Any] | None = None) -> Any:
    """:class:`bsp_ros.core.pipeline.IdentifyOptions` from the parsed options.

    Parameters
    ----------
    args : the parsed command line (with the options of :func:`add_identify_arguments`).
    body : body data known otherwise (``body_mass_kg``, ``height_m``, ``sex`` of a subject record); an
        option given on the command line wins.
    """
    from bsp_ros.core.fusion import SubjectInfo
    from bsp_ros.core.identification.passive import PassiveModel
    from bsp_ros.core.methods import Method
    from bsp_ros.core.pipeline import IdentifyOptions

    known = body or {}
    try:
        passive = PassiveModel() if args.passive is None else PassiveModel.parse(args.passive)
    except InputError as error:
        raise InputError(f"--passive {args.passive}: {error}") from None
    subject = SubjectInfo(
        args.body_mass if args.body_mass is not None else known.get("body_mass_kg"),
        args.height if args.height is not None else known.get("height_m"),
        args.sex or known.get("sex") or "male",
    )
    return IdentifyOptions(
        method=Method(args.method),
        passive=passive,
        elastic_fallback=args.passive is None,
        subject=subject,
        tare=read_tare(tare_path(args)),
        wrench_delay_s=args.wrench_delay_s,
        marker_placement_sd_m=args.marker_placement_sd_mm / 1000.0,
        handle_pose_sd_m=args.handle_pose_sd_mm / 1000.0,
        zero_sd_n=args.zero_sd_n,
        zero_sd_nm=args.zero_sd_nm,
    )


def options_record(args: argparse.Namespace, options: Any) -> dict[str, Any]:
    """What a stored session keeps of how it was identified: the settings, the body data and the tare file."""
    config = dict(options.config())
    topics = topics_from_args(args)
    config.update(
        {
            "body_mass_kg": options.subject.body_mass_kg,
            "height_m": options.subject.height_m,
            "sex": options.subject.sex,
            "tare_file": None if options.tare is None else Path(tare_path(args) or "").name,
            "wrench_topic": topics.wrench,
            "marker_topics": list(args.marker_topic),
            "handle_pose_topic": topics.handle_pose,
        }
    )
    return config


def add_trunk_tilt_argument(parser: argparse.ArgumentParser | Any) -> None:
    """``--trunk-tilt-deg DEG...``: one tilt per recording identified together."""
    parser.add_argument(
        "--trunk-tilt-deg",
        type=float,
        nargs="+",
        metavar="DEG",
        help="the trunk's tilt in each recording, deg, in the sense of the shoulder angle (world +y towards +z; "
        "default 0): a second posture turns gravity relative to the arm and separates elastic passive moments "
        "from gravity",
    )


def trunk_tilts_rad(tilts_deg: list[float] | None, n_recordings: int) -> list[float] | None:
    """The checked ``--trunk-tilt-deg`` values in rad (None when not given): one per recording, within +-90 deg."""
    if tilts_deg is None:
        return None
    if len(tilts_deg) != n_recordings:
        raise InputError(
            f"--trunk-tilt-deg gives {len(tilts_deg)} tilts ({' '.join(f'{t:g}' for t in tilts_deg)}) for "
            f"{n_recordings} recordings: give one per bag"
        )
    for tilt in tilts_deg:
        if not (math.isfinite(tilt) and abs(tilt) <= 90.0):
            raise InputError(f"--trunk-tilt-deg {tilt:g}: a tilt must be within -90..90 deg")
    return [math.radians(t) for t in tilts_deg]
