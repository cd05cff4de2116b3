"""`bsp identify BAG`: body segment parameters and passive moments of a recorded session."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from bsp_ros.cli.argtypes import positive_float
from bsp_ros.errors import BspError, DataError, InputError

# bsp_ros.core.pipeline.METHODS, spelled out here so the parser needs no scipy (a test keeps the two equal).
METHODS = ("joint", "paper")

# Distinct exit codes per failure, so scripts can tell them apart (0 valid, 1 written but invalid).
EXIT_INVALID = 1
BAG_EXIT_CODES = {
    "not-found": 10,
    "not-a-bag": 11,
    "empty": 12,
    "missing-topic": 13,
    "wrong-type": 14,
    "corrupt": 15,
    "unsupported": 16,
}


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp identify`."""
    parser = subparsers.add_parser(
        "identify",
        help="identify a recorded session (rosbag2 MCAP bag)",
        description="Identify static moments, masses, COMs and passive joint moments from a bag.",
    )
    parser.add_argument("bag", type=Path, help="rosbag2 directory or .mcap file")
    parser.add_argument("--json", type=Path, metavar="OUT", help="write the estimate (bsp_ros/core/estimate/1) here")
    parser.add_argument("--method", choices=METHODS, default="joint", help="joint (ours, default) or paper")
    parser.add_argument(
        "--passive", default="coulomb", metavar="MODEL", help="passive model, e.g. coulomb+viscous (default coulomb)"
    )
    parser.add_argument(
        "--body-mass", type=positive_float, metavar="KG", help="body mass for the anthropometric prior, kg"
    )
    parser.add_argument("--height", type=positive_float, metavar="M", help="body height for the prior, m")
    parser.add_argument("--sex", choices=("male", "female"), default="male", help="anthropometric table")
    parser.add_argument(
        "--wrench-topic", default="/ft_sensor/wrench", metavar="TOPIC", help="wrench topic (default /ft_sensor/wrench)"
    )
    parser.add_argument(
        "--marker-topic",
        action="append",
        default=[],
        metavar="NAME=TOPIC",
        help="remap a marker topic, e.g. elbow=/vicon/elbow (repeatable)",
    )
    parser.add_argument("--tf-topic", default="/tf", metavar="TOPIC", help="tf topic (default /tf)")
    parser.add_argument(
        "--tf-static-topic", default="/tf_static", metavar="TOPIC", help="static tf topic (default /tf_static)"
    )
    parser.add_argument(
        "--tare",
        type=Path,
        metavar="FILE",
        help="tare file of `bsp tare`: remove the sensor offset and handle load; its std joins the estimate's",
    )
    parser.add_argument(
        "--format",
        choices=("auto", "table", "tsv", "none"),
        default="auto",
        help="stdout: a table on a terminal, tab-separated values otherwise",
    )
    return parser


def _topics(args: argparse.Namespace) -> Any:
    from bsp_ros.bag import TopicMap

    markers = dict(TopicMap().markers)
    for item in args.marker_topic:
        name, _, topic = item.partition("=")
        if name not in markers or not topic:
            raise InputError(f"--marker-topic takes NAME=TOPIC with NAME in {sorted(markers)}, got {item!r}")
        if topic in (args.wrench_topic, args.tf_topic, args.tf_static_topic):
            raise InputError(f"--marker-topic {item}: {topic} is already the wrench or a tf topic")
        markers[name] = topic
    # A --wrench-topic that names a marker topic stays the wrench topic (TopicMap.expected_types), so a
    # PoseStamped topic given there fails the bag's type check (exit 14) before anything is decoded.
    return TopicMap(args.wrench_topic, markers, args.tf_static_topic, args.tf_topic)


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


def _progress_bar() -> Any:
    if not sys.stderr.isatty():
        return None

    def show(done: int, total: int) -> None:
        fraction = done / total if total else 1.0
        bar = "#" * int(40 * fraction)
        sys.stderr.write(f"\rreading [{bar:<40s}] {100 * fraction:5.1f}%")
        if done >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return show


def rows(document: dict[str, Any]) -> list[tuple[str, str, Any, Any, str]]:
    """(group, owner/key, value, std, source) for every quantity of an estimate document."""
    out = []
    for group in ("segments", "joints"):
        for owner, quantities in document[group].items():
            for key, q in quantities.items():
                out.append((owner, key, q["value"], q["std"], q["source"]))
    return out


def tare_line(quality: dict[str, Any]) -> str:
    """One line on the tare: applied (which file), or not, with how much 0.1 N of offset would matter."""
    tare = quality.get("tare") or {}
    if tare.get("applied"):
        return f"tare: {tare.get('file')} applied (its uncertainty is in the std)"
    percent = [p for p in (quality.get("offset_sensitivity") or {}).get("static_moment_percent", {}).values() if p]
    worst = f": 0.1 N of sensor offset moves a static moment by up to {max(percent):.2g}%" if percent else ""
    return f"tare: none applied{worst} (bsp tare, then --tare FILE)"


# Problems that mean the recording cannot be used at all (exit 3), as opposed to an estimate of doubtful quality.
_DATA_PROBLEMS = ("too few samples", "too few usable samples", "no motion at the ")


def data_problems(document: dict[str, Any]) -> list[str]:
    """The parts of an invalid estimate's message that say the data are too few or do not move (exit 3)."""
    quality = document["quality"]
    if quality["valid"]:
        return []
    parts = [part.strip() for part in str(quality.get("message", "")).split(";")]
    return [part for part in parts if part.startswith(_DATA_PROBLEMS)]


def _cell(value: Any) -> str:
    """One TSV cell: empty for a missing value, JSON-style booleans, no tab or newline inside."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(value).lower()
    return " ".join(str(value).split())


TSV_HEADER = ("owner", "parameter", "value", "std", "source")


def format_tsv(document: dict[str, Any]) -> str:
    """Tab-separated values: a header, then five columns on every row (empty where there is nothing).

    The first rows are the verdict (`quality valid`, `quality message`) and the tare note (`quality tare`),
    then one row per quantity.
    """
    quality = document["quality"]
    table: list[tuple[Any, ...]] = [
        TSV_HEADER,
        ("quality", "valid", quality["valid"], None, None),
        ("quality", "message", quality.get("message"), None, None),
        ("quality", "tare", tare_line(quality).removeprefix("tare: "), None, None),
        *rows(document),
    ]
    return "\n".join("\t".join(_cell(value) for value in row) for row in table)


def format_table(document: dict[str, Any]) -> str:
    """A human-readable table of an estimate document."""
    quality = document["quality"]
    condition = quality["condition_number"]
    condition_text = "n/a" if condition is None else f"{condition:.3g}"
    lines = [
        f"method: {document['method']}   samples: {quality['n_samples']}   condition number: {condition_text}",
        f"{'':10s} {'parameter':22s} {'value':>12s} {'+- std':>11s}  source",
    ]
    for owner, key, value, std, source in rows(document):
        value_text = "n/a" if value is None else f"{value:.5g}"
        std_text = "n/a" if std is None else f"{std:.2g}"
        lines.append(f"{owner:10s} {key:22s} {value_text:>12s} {std_text:>11s}  {source}")
    lines.append(tare_line(quality))
    state = "VALID" if quality["valid"] else "INVALID"
    lines.append(f"{state}: {quality.get('message', '')}")
    lines += [f"warning: {w}" for w in quality["warnings"]]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Identify the bag; print the result; write the JSON."""
    from bsp_ros.bag.errors import BagError
    from bsp_ros.bag.offline import identify_bag
    from bsp_ros.core.fusion import SubjectInfo
    from bsp_ros.core.identification.passive import PassiveModel
    from bsp_ros.core.pipeline import IdentifyOptions
    from bsp_ros.validation import check_output_file

    # Before the identification: a result that cannot be written is not worth computing.
    json_path = None if args.json is None else check_output_file("--json", args.json)
    try:
        passive = PassiveModel.parse(args.passive)
    except InputError as error:
        raise InputError(f"--passive {args.passive}: {error}") from None
    options = IdentifyOptions(
        method=args.method,
        passive=passive,
        subject=SubjectInfo(args.body_mass, args.height, args.sex),
        tare=read_tare(args.tare),
    )
    try:
        document = identify_bag(args.bag, options, _topics(args), _progress_bar())
    except BagError as error:
        print(f"bsp identify: error: {error}", file=sys.stderr)
        return BAG_EXIT_CODES.get(getattr(error, "code", ""), error.exit_code)
    except BspError:
        raise
    unusable = data_problems(document)
    if unusable:
        # One rule for too little data, however little (README "Exit codes": 3), whichever stage noticed it.
        raise DataError(f"the data cannot be used: {'; '.join(unusable)}")
    if json_path is not None:
        text = json.dumps(document, indent=2, allow_nan=False) + "\n"
        try:
            json_path.parent.mkdir(parents=True, exist_ok=True)
            json_path.write_text(text)
        except OSError as error:  # checked above; this is a disk that filled or changed since
            raise InputError(f"--json {json_path}: cannot write ({error.strerror})") from None
    output = args.format if args.format != "auto" else ("table" if sys.stdout.isatty() else "tsv")
    if output == "table":
        print(format_table(document))
    elif output == "tsv":
        print(format_tsv(document))
    if output != "table":
        # The table says all of this on stdout; otherwise stdout is data, and the reasons go to stderr.
        quality = document["quality"]
        if not quality["valid"]:
            print(f"bsp identify: estimate INVALID: {quality.get('message', '')}", file=sys.stderr)
        for warning in quality["warnings"] if output == "tsv" else ():
            print(f"warning: {warning}", file=sys.stderr)
    return 0 if document["quality"]["valid"] else EXIT_INVALID
