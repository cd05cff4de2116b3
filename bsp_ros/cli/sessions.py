"""`bsp sessions`: add identified sessions to the store, list, show, erase and export them."""

from __future__ import annotations

import argparse
import importlib
import json
import sys
from pathlib import Path
from typing import Any

from bsp_ros.clinic.store import (
    WALL_CLOCK_START_NS,
    SessionRecord,
    Store,
    format_time,
    load_estimate_file,
    open_store,
    parse_time_ns,
    write_sessions_csv,
)
from bsp_ros.clinic.store.subject import check_pseudonymous_id
from bsp_ros.errors import InputError, StoreError

BAG_SUFFIXES = (".mcap", ".db3", ".bag")


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Register `bsp sessions` and its actions."""
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument(
        "--store",
        metavar="LOCATION",
        help="SQLite file or postgresql:// URL (default: $BSP_STORE, else ~/.local/share/bsp_ros/sessions.sqlite)",
    )
    parser = subparsers.add_parser(
        "sessions",
        help="keep identified sessions per pseudonymous subject",
        description="Keep identified sessions per pseudonymous subject id (never a name).",
    )
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    add = actions.add_parser("add", parents=[common], help="store a result JSON or identify and store a bag")
    add.add_argument("input", metavar="RESULT.json|BAG", help="a `bsp identify --json` result or a bag")
    add.add_argument("--subject", required=True, metavar="ID", help="pseudonymous subject id [A-Za-z0-9_-]{1,64}")
    add.add_argument(
        "--time",
        metavar="TIME",
        help="session start: a date (2024-03-01), ISO 8601 (2024-03-01T09:30Z, naive = UTC) or epoch seconds; "
        "needed when the recording is not stamped by a wall clock",
    )
    add.add_argument("--source", metavar="NAME", help="recording name, if the input lacks it (default: file name)")
    add.add_argument(
        "--allow-identifying-id",
        action="store_true",
        help="store a subject id even though it looks like a person's name or a birth date",
    )
    actions.add_parser("list", parents=[common], help="list subjects and their session counts")
    show = actions.add_parser("show", parents=[common], help="show a subject's sessions and parameters")
    show.add_argument("subject", metavar="SUBJECT")
    show.add_argument("--json", action="store_true", help="print the sessions as JSON")
    erase = actions.add_parser("erase", parents=[common], help="erase every session of a subject, leaving no bytes")
    erase.add_argument("subject", metavar="SUBJECT")
    export = actions.add_parser("export", parents=[common], help="export sessions")
    export.add_argument("--csv", required=True, metavar="FILE", help="CSV file to write ('-' for stdout)")
    export.add_argument("--subject", metavar="ID", help="only this subject")
    actions.add_parser("compact", parents=[common], help="rewrite the store so deleted rows leave no bytes")
    return parser


def run(args: argparse.Namespace) -> int:
    """Run one `bsp sessions` action; return the exit code."""
    with open_store(args.store) as store:
        if args.action == "add":
            return _add(store, args)
        if args.action == "list":
            return _list(store)
        if args.action == "show":
            return _show(store, args.subject, as_json=args.json)
        if args.action == "erase":
            count = store.erase(args.subject)
            print(f"erased {count} session(s) of {args.subject} from {store.location}")
            return 0
        if args.action == "export":
            return _export(store, args.csv, args.subject)
        store.compact()
        print(f"compacted {store.location}")
        return 0


def is_bag(path: Path) -> bool:
    """Whether ``path`` looks like a recording (a rosbag2 directory or a bag file) rather than a result."""
    return path.is_dir() or path.suffix.lower() in BAG_SUFFIXES


def _identify_bag(path: Path) -> dict[str, Any]:
    try:
        identify_bag = getattr(importlib.import_module("bsp_ros.bag.offline"), "identify_bag", None)
        problem = "bsp_ros.bag.offline has no identify_bag"
    except ImportError as error:
        identify_bag, problem = None, f"bsp_ros.bag.offline cannot be imported: {error}"
    if identify_bag is None:
        raise StoreError(
            f"cannot identify bag {path} here ({problem}); "
            "run `bsp identify BAG --json RESULT.json` and add RESULT.json"
        )
    estimate = identify_bag(path)
    if not isinstance(estimate, dict):
        raise StoreError(f"identify_bag({path}) returned a {type(estimate).__name__}, not an estimate dict")
    if "repeatability" not in estimate:
        estimate["repeatability"] = bag_repeatability(path)
    return estimate


def bag_repeatability(path: Path) -> dict[str, Any] | None:
    """The ``repeatability`` block (SEM and MDC95 per parameter, :mod:`bsp_ros.clinic.mdc`) of a bag, or None.

    Each full cycle of motion is identified on its own with the default settings of `bsp identify`;
    a bag that cannot be read for this gives None (and a note), not an error: the estimate is stored anyway.
    """
    from bsp_ros.bag import read_session
    from bsp_ros.clinic.mdc import repeatability
    from bsp_ros.core.identification.data import identification_data_from_session
    from bsp_ros.core.identification.joint import JointConfig
    from bsp_ros.core.pipeline import IdentifyOptions
    from bsp_ros.errors import BspError

    options = IdentifyOptions()
    try:
        data = identification_data_from_session(read_session(path).session, options.kinematics)
        found = repeatability(data, JointConfig(passive=options.passive))
    except BspError as error:
        print(f"note: no repeatability (MDC) for {path.name}: {error}")
        return None
    if found.message:
        print(f"note: no repeatability (MDC) for {path.name}: {found.message}")
    return found.to_json()


def recorded_start_ns(path: Path) -> int | None:
    """The bag's recorded start (its first receive time, ns), or None if it records none.

    A rosbag2 directory's ``metadata.yaml`` ``starting_time``, else an MCAP file's summary statistics.
    """
    try:
        if path.is_dir():
            import yaml

            info = yaml.safe_load((path / "metadata.yaml").read_text("utf-8"))["rosbag2_bagfile_information"]
            return int(info["starting_time"]["nanoseconds_since_epoch"])
        from mcap.reader import make_reader

        with path.open("rb") as stream:
            summary = make_reader(stream).get_summary()
        if summary is None or summary.statistics is None or not summary.statistics.message_count:
            return None
        return int(summary.statistics.message_start_time)
    except Exception:
        return None


def _session_time_ns(args: argparse.Namespace, path: Path, estimate: dict[str, Any]) -> int | None:
    """The session time to store: ``--time``, else the estimate's if wall-clock, else the bag's recorded start."""
    if args.time is not None:
        return parse_time_ns(args.time)
    block = estimate.get("session")
    stamped = block.get("start_time_ns") if isinstance(block, dict) else None
    if not isinstance(stamped, int) or isinstance(stamped, bool) or stamped >= WALL_CLOCK_START_NS:
        return None  # the estimate's own time (or its absence) is checked when it is parsed
    recorded = recorded_start_ns(path) if is_bag(path) else None
    if recorded is not None and recorded >= WALL_CLOCK_START_NS:
        print(
            f"note: the data are stamped from {stamped / 1e9:.6g} s (boot or simulated time, not a wall clock); "
            f"using the bag's recorded start {format_time(recorded)}"
        )
        return recorded
    where = "its recorded start is not wall-clock either" if is_bag(path) else "a result JSON has no other clock"
    raise InputError(
        f"{path.name}: the data are stamped from {stamped / 1e9:.6g} s after 1970-01-01 (a controller's boot "
        f"time or simulated time, not a wall clock) and {where}; give the session start with --time "
        "(a date 2024-03-01, ISO 8601 2024-03-01T09:30Z or epoch seconds)"
    )


def _add(store: Store, args: argparse.Namespace) -> int:
    # Before any slow identification.
    subject = check_pseudonymous_id(args.subject, allow_identifying=args.allow_identifying_id)
    path = Path(args.input)
    if not path.exists():
        raise InputError(f"{path} does not exist")
    estimate = _identify_bag(path) if is_bag(path) else load_estimate_file(path)
    session = estimate.get("session") if isinstance(estimate.get("session"), dict) else {}
    source = args.source or (None if session and session.get("source") else path.name)
    record = store.add_estimate(
        estimate,
        subject,
        session_time_ns=_session_time_ns(args, path, estimate),
        source=source,
    )
    # Printed only after the commit returned: the session is durable.
    print(
        f"added session {record.id} of {record.subject} at {format_time(record.session_time_ns)} "
        f"from {record.source} ({'valid' if record.quality.valid else 'NOT VALID'}, "
        f"{len(record.parameters)} parameters)"
    )
    return 0


def _list(store: Store) -> int:
    subjects = store.subjects()
    if not subjects:
        print(f"no sessions in {store.location}")
        return 0
    print(f"{'subject':<24} {'sessions':>8} {'not valid':>9}  first                 last")
    for s in subjects:
        print(
            f"{s.subject:<24} {s.n_sessions:>8} {s.n_invalid:>9}  "
            f"{format_time(s.first_ns):<21} {format_time(s.last_ns)}"
        )
    return 0


def _show(store: Store, subject: str, *, as_json: bool) -> int:
    records = store.sessions(subject)
    if as_json:
        json.dump([record_to_json(r) for r in records], sys.stdout, indent=2)
        print()
        return 0
    for record in records:
        quality = record.quality
        print(
            f"session {record.id}  {format_time(record.session_time_ns)}  {record.source}  "
            f"method={record.method or '-'}  {'valid' if quality.valid else 'NOT VALID'}"
        )
        for warning in quality.warnings:
            print(f"  warning: {warning}")
        for (_group, part, quantity), q in record.parameters.items():
            value = "-" if q.value is None else f"{q.value:.6g}"
            std = "-" if q.std is None else f"{q.std:.3g}"
            print(f"  {part + '.' + quantity:<32} {value:>12} ± {std:<10} ({q.source})")
    return 0


def _export(store: Store, target: str, subject: str | None) -> int:
    records = store.sessions(subject)
    if target == "-":
        rows = write_sessions_csv(records, sys.stdout)
    else:
        try:
            with open(target, "w", newline="", encoding="utf-8") as stream:
                rows = write_sessions_csv(records, stream)
        except OSError as error:
            raise InputError(f"cannot write {target}: {error}") from None
        print(f"wrote {rows} rows ({len(records)} sessions) to {target}")
    return 0


def record_to_json(record: SessionRecord) -> dict[str, Any]:
    """``record`` as a JSON-ready dict (the estimate layout plus the session block)."""
    body: dict[str, Any] = {
        "schema": record.estimate_schema,
        "segments": {},
        "joints": {},
        "quality": {
            "valid": record.quality.valid,
            "n_samples": record.quality.n_samples,
            "condition_number": record.quality.condition_number,
            "residual_rms_nm": record.quality.residual_rms_nm,
            "warnings": list(record.quality.warnings),
            "tare": {"applied": record.quality.tare_applied, "file": record.quality.tare_file},
        },
        "session": {
            "subject": record.subject,
            "start_time_ns": record.session_time_ns,
            "source": record.source,
            "method": record.method,
            "config": record.config,
        },
        "subject": record.subject_info,
    }
    if record.repeatability:
        body["repeatability"] = record.repeatability
    for (group, part, quantity), q in record.parameters.items():
        body[group].setdefault(part, {})[quantity] = {"value": q.value, "std": q.std, "source": q.source}
    return body
