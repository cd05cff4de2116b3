"""`bsp identify BAG [BAG ...]`: body segment parameters and passive moments of recorded sessions."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from bsp_ros.cli.argtypes import int_within
from bsp_ros.cli.identify_options import (  # noqa: F401
    METHODS,
    add_identify_arguments,
    add_trunk_tilt_argument,
    options_from_args,
    topics_from_args,
    trunk_tilts_rad,
)

# METHODS (bsp_ros.core.pipeline's, spelled out so the parser needs no scipy; a test keeps the two equal).
from bsp_ros.core.estimate_schema import Estimate, Quality
from bsp_ros.core.findings import FindingCode, invalid_texts, plain_cause
from bsp_ros.errors import BspError, DataError, InputError

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
    parser.add_argument(
        "bag",
        type=Path,
        nargs="+",
        help="rosbag2 directory or .mcap file; several: recordings of the same arm identified together",
    )
    add_trunk_tilt_argument(parser)
    parser.add_argument(
        "--json", type=Path, metavar="OUT", help="write the estimate (bsp_ros/core/estimate/1) here ('-': stdout)"
    )
    add_identify_arguments(parser)
    parser.add_argument(
        "--format",
        choices=("auto", "table", "tsv", "none"),
        default="auto",
        help="stdout: a table on a terminal, tab-separated values otherwise (nothing with --json -)",
    )
    add_each_arguments(parser)
    return parser


def add_each_arguments(parser: argparse.ArgumentParser) -> None:
    """The options of `bsp identify --each` (every bag its own session: bsp_ros.cli.identify_each)."""
    parser.add_argument(
        "--each",
        action="store_true",
        help="every bag its own session (a folder of bags: each bag inside); needs --json-dir and --summary",
    )
    parser.add_argument("--json-dir", type=Path, metavar="DIR", help="with --each: one <bag name>.json per bag here")
    parser.add_argument(
        "--summary",
        type=Path,
        metavar="FILE",
        help="with --each: a CSV row per bag (exit code, verdict, cause, parameters with std; '-': stdout)",
    )
    parser.add_argument(
        "--jobs", type=int_within(1, 256), metavar="N", help="with --each: N worker processes (default 1)"
    )


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


def rows(estimate: Estimate) -> list[tuple[str, str, float | None, float | None, str]]:
    """(owner, key, value, std, source) for every quantity of an estimate, then each joint's passive curve point by
    point (``passive_moment_nm@<angle>deg``) and its stiffness at the reference angle."""
    out: list[tuple[str, str, float | None, float | None, str]] = [
        (owner, key, q.value, q.std, str(q.source)) for _, owner, key, q in estimate.quantities()
    ]
    for joint, curve in estimate.passive_curves.items():
        for angle, moment, std in zip(curve["angle_deg"], curve["moment_nm"], curve["std_nm"], strict=True):
            out.append((joint, f"passive_moment_nm@{angle:.1f}deg", moment, std, "data"))
        if curve.get("reference_angle_deg") is not None:
            key = f"passive_stiffness_nm_per_rad@{curve['reference_angle_deg']:.1f}deg"
            out.append((joint, key, curve.get("stiffness_nm_per_rad"), curve.get("stiffness_std_nm_per_rad"), "data"))
    return out


def tare_line(quality: Quality) -> str:
    """One line on the tare: applied (which file), or not, with how much 0.1 N of offset would matter."""
    if quality.tare_applied:
        return f"tare: {quality.tare_file} applied (its uncertainty is in the std)"
    sensitivity = quality.extra.get("offset_sensitivity") or {}
    percent = [p for p in sensitivity.get("static_moment_percent", {}).values() if p]
    worst = f": 0.1 N of sensor offset moves a static moment by up to {max(percent):.2g}%" if percent else ""
    zero = quality.tare.zero_sd if quality.tare is not None else None
    assumed = f"; the std assumes the sensor's zero within {zero.force_n:g} N" if zero and zero.force_n else ""
    return f"tare: none applied{worst}{assumed} (bsp tare, then --tare FILE)"


# Findings that mean the recording cannot be used at all (exit 3), as opposed to an estimate of doubtful quality.
DATA_PROBLEMS = frozenset({FindingCode.TOO_FEW_SAMPLES, FindingCode.TOO_FEW_USABLE_SAMPLES, FindingCode.NO_MOTION})


def data_problems(estimate: Estimate) -> list[str]:
    """The texts of an invalid estimate's findings that say the data are too few or do not move (exit 3)."""
    if estimate.valid:
        return []
    return [f.text for f in estimate.quality.findings if f.code in DATA_PROBLEMS]


def _cell(value: Any) -> str:
    """One TSV cell: empty for a missing value, JSON-style booleans, no tab or newline inside."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return str(value).lower()
    return " ".join(str(value).split())


TSV_HEADER = ("owner", "parameter", "value", "std", "source")


def format_tsv(estimate: Estimate) -> str:
    """Tab-separated values: a header, then five columns on every row (empty where there is nothing).

    The first rows are the verdict (`quality valid`, `quality message`) and the tare note (`quality tare`),
    then one row per quantity.
    """
    quality = estimate.quality
    table: list[tuple[Any, ...]] = [
        TSV_HEADER,
        ("quality", "valid", quality.valid, None, None),
        ("quality", "message", quality.message, None, None),
        ("quality", "tare", tare_line(quality).removeprefix("tare: "), None, None),
        *rows(estimate),
    ]
    return "\n".join("\t".join(_cell(value) for value in row) for row in table)


def verdict_lines(estimate: Estimate) -> list[str]:
    """The verdict: ``VALID: <summary>``, or ``INVALID: <cause>; <action>`` in plain words and then each reason
    the estimator found, once."""
    quality = estimate.quality
    if quality.valid:
        return [f"VALID: {quality.message}"]
    plain = plain_cause(quality.findings)
    reasons = list(dict.fromkeys(invalid_texts(quality.findings))) or [quality.message]
    if plain is None:
        return [f"INVALID: {reasons[0]}", *(f"  because: {r}" for r in reasons[1:])]
    cause, action = plain
    return [f"INVALID: {cause}; {action}", *(f"  because: {r}" for r in reasons)]


def largest_uncertainty(estimate: Estimate) -> str | None:
    """Which source of uncertainty weighs most in the static moments' std, and what would shrink it."""
    from bsp_ros.core.identification.ledger import Term

    shares: dict[str, list[float]] = {}
    for quantities in estimate.segments.values():
        largest = quantities["static_moment_kgm"].largest_term() if "static_moment_kgm" in quantities else None
        if largest is not None:
            shares.setdefault(largest[0], []).append(largest[1])
    if not shares:
        return None
    term = max(shares, key=lambda t: (len(shares[t]), max(shares[t])))
    remedy = Term(term).remedy if term in {t.value for t in Term} else ""
    return (
        f"uncertainty: the static moments' std is mostly {term.replace('_', ' ')} (up to "
        f"{100 * max(shares[term]):.0f} % of the variance){': ' + remedy if remedy else ''}"
    )


def format_table(estimate: Estimate) -> str:
    """A human-readable table of an estimate."""
    quality = estimate.quality
    condition = quality.condition_number
    condition_text = "n/a" if condition is None else f"{condition:.3g}"
    lines = [
        f"method: {estimate.method}   samples: {quality.n_samples}   condition number: {condition_text}",
        f"{'':10s} {'parameter':22s} {'value':>12s} {'+- std':>11s}  source",
    ]
    for owner, key, value, std, source in rows(estimate):
        value_text = "n/a" if value is None else f"{value:.5g}"
        std_text = "n/a" if std is None else f"{std:.2g}"
        lines.append(f"{owner:10s} {key:22s} {value_text:>12s} {std_text:>11s}  {source}")
    lines.append(tare_line(quality))
    uncertainty = largest_uncertainty(estimate) if quality.valid else None
    lines += [uncertainty] if uncertainty else []
    lines += verdict_lines(estimate)
    lines += [f"warning: {w}" for w in quality.warnings]
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    """Identify the bag; print the result; write the JSON."""

    from bsp_ros.bag.errors import BagError
    from bsp_ros.bag.offline import estimate_bags
    from bsp_ros.cli.identify_each import check_each_args, run_each
    from bsp_ros.validation import check_output_file

    check_each_args(args)
    if args.each:
        return run_each(args)
    # `--json -` is the estimate on stdout, and then stdout is nothing else (as `sessions export --csv -`).
    json_stdout = args.json is not None and str(args.json) == "-"
    if json_stdout and args.format in ("table", "tsv"):
        raise InputError(f"--json - writes the estimate to stdout: --format {args.format} would mix into it")
    # Before the identification: a result that cannot be written is not worth computing.
    json_path = None if args.json is None or json_stdout else check_output_file("--json", args.json)
    options = options_from_args(args)
    tilts_rad = trunk_tilts_rad(args.trunk_tilt_deg, len(args.bag))
    topics = topics_from_args(args)
    try:
        estimate = estimate_bags(args.bag, options, topics, _progress_bar(), tilts_rad)
    except BagError as error:
        print(f"bsp identify: error: {error}", file=sys.stderr)
        return BAG_EXIT_CODES.get(getattr(error, "code", ""), error.exit_code)
    except InputError as error:
        if len(args.bag) < 2:
            raise
        # Bags given together are one arm's recordings in sequence; where they are not, say how to take them apart.
        raise InputError(
            f"{error}; each bag its own session: bsp identify --each BAG... --json-dir DIR --summary FILE"
        ) from None
    except BspError:
        raise
    unusable = data_problems(estimate)
    if unusable:
        # One rule for too little data, however little (README "Exit codes": 3), whichever stage noticed it.
        raise DataError(f"the data cannot be used: {'; '.join(unusable)}")
    if json_stdout:
        sys.stdout.write(json.dumps(estimate.to_json(), indent=2, allow_nan=False) + "\n")
    if json_path is not None:
        text = json.dumps(estimate.to_json(), indent=2, allow_nan=False) + "\n"
        try:
            json_path.parent.mkdir(parents=True, exist_ok=True)
            json_path.write_text(text)
        except OSError as error:  # checked above; this is a disk that filled or changed since
            raise InputError(f"--json {json_path}: cannot write ({error.strerror})") from None
    output = args.format if args.format != "auto" else ("table" if sys.stdout.isatty() else "tsv")
    output = "none" if json_stdout else output
    if output == "table":
        print(format_table(estimate))
    elif output == "tsv":
        print(format_tsv(estimate))
    if output != "table":
        # The table says all of this on stdout; otherwise stdout is data, and the reasons go to stderr.
        if not estimate.valid:
            first, *details = verdict_lines(estimate)
            print(f"bsp identify: estimate {first}", file=sys.stderr)
            for line in details:
                print(line, file=sys.stderr)
        for warning in estimate.quality.warnings if output == "tsv" else ():
            print(f"warning: {warning}", file=sys.stderr)
    return 0 if estimate.valid else EXIT_INVALID
