"""The actions of `bsp sessions` (add, list, show, remove, erase, export, compact) on a session store."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

from bsp_ros.clinic.store import (
    WALL_CLOCK_START_NS,
    SessionRecord,
    Store,
    SubjectRecord,
    format_time,
    load_estimate_file,
    open_store,
    parse_time_ns,
)
from bsp_ros.clinic.store.estimate import check_future
from bsp_ros.clinic.store.records import Quality, describe_body
from bsp_ros.clinic.store.subject import check_pseudonymous_id
from bsp_ros.core.findings import Finding, Severity, invalid_texts, plain_cause
from bsp_ros.errors import InputError, StoreError


def verdict_text(quality: Quality) -> str:
    """Why a stored session is not valid: the cause and what to do, in plain words, and the estimator's first
    reason (a session stored before findings existed: its message)."""
    plain = plain_cause(quality.findings)
    if plain is None:
        return quality.message or "no reason recorded"
    cause, action = plain
    first = next(iter(invalid_texts(quality.findings)), "")
    return f"{cause}; {action} ({first})" if first else f"{cause}; {action}"


def run_action(args: argparse.Namespace) -> int:
    """Run one `bsp sessions` action; return the exit code."""
    if args.action == "add":
        with open_store(args.store) as store:
            return _add(store, args)
    with open_store(args.store, create=False) as store:
        if args.action == "list":
            return _list(store)
        if args.action == "show":
            return _show(store, args.subject, as_json=args.json)
        if args.action == "remove":
            return _remove(store, args.subject, args.number, args.yes)
        if args.action == "erase":
            return _erase(store, args.subject, args.yes)
        if args.action == "export":
            return _export(store, args.csv, args.subject)
        store.compact()
        print(f"compacted {store.location}")
        return 0


def confirm(question: str, yes: bool, what: str) -> None:
    """Ask ``question`` on the terminal unless ``yes``; refuse (InputError) when not answered yes."""
    if yes:
        return
    if not sys.stdin.isatty():
        raise InputError(f"{what} cannot be undone: confirm with --yes (not asked: no terminal)")
    answer = input(f"{question} This cannot be undone. Type yes to go on: ").strip().lower()
    if answer != "yes":
        raise InputError(f"{what}: not confirmed, nothing was changed")


def _remove(store: Store, subject: str, number: int, yes: bool) -> int:
    records = store.sessions(subject)
    if 1 <= number <= len(records):
        target = records[number - 1]
        confirm(
            f"Remove session {number} of {subject} ({format_time(target.session_time_ns)}, {target.source})?",
            yes,
            f"removing session {number} of {subject}",
        )
    removed = store.remove(subject, number)
    print(
        f"removed session {number} of {subject} ({format_time(removed.session_time_ns)}, {removed.source}); "
        "later sessions are renumbered"
    )
    return 0


def _erase(store: Store, subject: str, yes: bool) -> int:
    try:
        count = len(store.sessions(subject))
    except StoreError:
        count = 0
        if store.subject_record(subject) is None:
            raise
    confirm(f"Erase all {count} session(s) and the subject record of {subject}?", yes, f"erasing {subject}")
    erased = store.erase(subject)
    print(f"erased {erased} session(s) of {subject} from {store.location}")
    return 0


def is_bag(path: Path) -> bool:
    """Whether ``path`` looks like a recording (a rosbag2 directory or a bag file) rather than a result."""
    from bsp_ros.bag.fingerprint import BAG_SUFFIXES  # here: the bag package pulls in numpy, not needed to start

    return path.is_dir() or path.suffix.lower() in BAG_SUFFIXES


def identify_bag_for_store(
    path: Path | list[Path], args: argparse.Namespace, body: dict[str, Any], sha256: str | None = None
) -> dict[str, Any]:
    """The estimate of a bag (or of several bags of one session, ``args.trunk_tilt_deg`` one tilt each) identified
    with the `bsp identify` options of ``args`` (body data default to ``body``), with its within-session
    repeatability (of the first recording), the options and the content hash (``sha256`` if given)."""
    from bsp_ros.bag import read_session
    from bsp_ros.bag.offline import estimate_from_read, estimate_from_reads
    from bsp_ros.cli.identify_options import options_from_args, options_record, topics_from_args, trunk_tilts_rad
    from bsp_ros.clinic.cycles import cycle_repeatability

    paths = path if isinstance(path, list) else [path]
    tilts_rad = trunk_tilts_rad(getattr(args, "trunk_tilt_deg", None), len(paths))
    options = options_from_args(args, body)
    # Each bag read once: the estimate and the first recording's cycles share it.
    reads = [read_session(p, topics=topics_from_args(args)) for p in paths]
    if len(paths) == 1 and not any(tilts_rad or ()):
        estimate = estimate_from_read(reads[0], paths[0], options, sha256=sha256)
    else:
        estimate = estimate_from_reads(reads, paths, options, tilts_rad)
    found = cycle_repeatability(reads[0].session, options)
    if found.message:
        print(f"note: no within-session repeatability for {paths[0].name}: {found.message}")
    estimate["repeatability"] = found.to_json()
    # identify_bag(s) put the recordings' content_sha256 in the session block: the store's duplicate check.
    config = options_record(args, options)
    if tilts_rad is not None:
        config["trunk_tilt_deg"] = list(args.trunk_tilt_deg)
    estimate.setdefault("session", {})["config"] = config
    return estimate


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
    """The session time to store when ``--time`` is not given: None for the estimate's own (wall-clock) time,
    else the bag's recorded start."""
    block = estimate.get("session")
    stamped = block.get("start_time_ns") if isinstance(block, dict) else None
    if not isinstance(stamped, int) or isinstance(stamped, bool) or stamped >= WALL_CLOCK_START_NS:
        return None  # the estimate's own time (or its absence) is checked when it is parsed
    recorded = recorded_start_ns(path) if is_bag(path) else None
    if recorded is not None and recorded >= WALL_CLOCK_START_NS:
        print(
            f"note: the data are stamped from {stamped / 1e9:.6g} s (boot or simulated time, not a wall clock); "
            f"using the bag's recorded start {format_time(recorded)} as the session time (give --time to set another)"
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
    paths = [Path(p) for p in args.input]
    for path in paths:
        if not path.exists():
            raise InputError(f"{path} does not exist")
    path = paths[0]
    if len(paths) > 1 and not all(is_bag(p) for p in paths):
        raise InputError("several inputs are the recordings of one session: give bags only (or one result JSON)")
    if args.trunk_tilt_deg is not None and not is_bag(path):
        raise InputError("--trunk-tilt-deg applies to bags; a result JSON keeps the tilts it was made with")
    time_ns = None if args.time is None else parse_time_ns(args.time)
    if time_ns is not None:
        check_future(time_ns, time.time_ns(), "--time")
    known = store.subject_record(subject)
    if is_bag(path):
        from bsp_ros.bag.fingerprint import content_sha256, recordings_sha256

        # A stored recording is refused before it is identified (the same check runs again on adding).
        several = len(paths) > 1 or any(args.trunk_tilt_deg or ())
        sha256 = recordings_sha256(paths)[0] if several else content_sha256(path)
        store.refuse_stored_content(sha256)
        body = known.body() if known is not None else {}
        estimate = identify_bag_for_store(paths, args, body, sha256)
    else:
        estimate = load_estimate_file(path)
    session = estimate.get("session") if isinstance(estimate.get("session"), dict) else {}
    source = args.source or (None if session and session.get("source") else path.name)
    stored_time = time_ns if time_ns is not None else _session_time_ns(args, path, estimate)
    record = store.add_estimate(
        estimate,
        subject,
        session_time_ns=stored_time,
        source=source,
        arm=args.arm,
        retest=True if args.retest else None,
        cell=args.cell or None,
    )
    if time_ns is None and stored_time is None:
        print(
            f"session time {format_time(record.session_time_ns)} taken from the recording's own stamps "
            "(give --time to set another)"
        )
    # Printed only after the commit returned: the session is durable.
    kind = "retest" if record.retest else "session"
    arm = f", {record.arm} arm" if record.arm else ""
    print(
        f"added {kind} {record.number} of {record.subject}{arm} at {format_time(record.session_time_ns)} "
        f"from {record.source} ({'valid' if record.quality.valid else 'NOT VALID'}, "
        f"{len(record.parameters)} parameters)"
    )
    if not record.quality.valid:
        print(f"  not valid: {verdict_text(record.quality)}")
    if known is not None and known.differs_from(record.subject_info):
        print(_body_warning(path, record, known), file=sys.stderr)
    untared = _untared_warning(store, record)
    if untared:
        print(untared, file=sys.stderr)
    return 0


def _untared_warning(store: Store, record: SessionRecord) -> str | None:
    """One line where a session without a tare joins a subject's tared sessions of the same arm: a sensor offset or
    the handle's weight may sit in its arm weight, which the report and the weight support then leave out."""
    if record.quality.tare_applied or not record.quality.valid:
        return None
    tared = [
        r
        for r in store.sessions(record.subject)
        if r.id != record.id and r.arm == record.arm and r.quality.valid and r.quality.tare_applied
    ]
    if not tared:
        return None
    return (
        f"warning: session {record.number} of {record.subject} has no tare while {len(tared)} of its sessions do: "
        "a sensor offset or the handle's weight may be in its arm weight, so the report keeps its passive moments "
        "but not its arm weight, and the weight support comes from a tared session (record a tare: bsp tare, "
        "then --tare FILE)"
    )


def _body_warning(path: Path, record: SessionRecord, known: SubjectRecord) -> str:
    """One line: the session's masses come from other body data than the subject record's, and how to fix it."""
    said = (
        f"warning: {path.name} was identified with body data {describe_body(record.subject_info)}, not "
        f"{record.subject}'s record ({describe_body(known.body())}): its masses and centres of mass come from that "
        "prior and are stored with it"
    )
    if is_bag(path):
        return f"{said} (the body data given here override the record)"
    return (
        f"{said}; to use the record, add the bag itself (`bsp sessions add BAG --subject {record.subject}`) or make "
        f"the result with `bsp identify BAG {known.identify_options()} --json RESULT.json`"
    )


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
        marks = [record.arm or "", "retest" if record.retest else ""]
        print(
            f"session {record.number}  {format_time(record.session_time_ns)}  {record.source}  "
            f"method={record.method or '-'}  {'valid' if quality.valid else 'NOT VALID'}  "
            + " ".join(m for m in marks if m)
        )
        if not quality.valid:
            print(f"  not valid: {verdict_text(quality)}")
        for warning in quality.warnings:
            print(f"  warning: {warning}")
        for (_group, part, quantity), q in record.parameters.items():
            value = "-" if q.value is None else f"{q.value:.6g}"
            std = "-" if q.std is None else f"{q.std:.3g}"
            print(f"  {part + '.' + quantity:<32} {value:>12} ± {std:<10} ({q.source})")
    return 0


def _export(store: Store, target: str, subject: str | None) -> int:
    from bsp_ros.clinic.report.analysis import analyse
    from bsp_ros.clinic.report.export import write_analysis_csv

    everyone = store.sessions()
    subjects = [subject] if subject is not None else sorted({r.subject for r in everyone})
    analyses = [analyse(s, store.sessions(s), pool=everyone, subject_record=store.subject_record(s)) for s in subjects]
    if target == "-":
        rows = write_analysis_csv(analyses, sys.stdout)
    else:
        try:
            with open(target, "w", newline="", encoding="utf-8") as stream:
                rows = write_analysis_csv(analyses, stream)
        except OSError as error:
            raise InputError(f"cannot write {target}: {error}") from None
        print(f"wrote {rows} rows ({sum(len(a.sessions) for a in analyses)} sessions) to {target}")
    return 0


def finding_to_json(finding: Finding) -> dict[str, Any]:
    """A stored finding as the estimate writes it (``code``, ``severity``, ``where``, ``text``, ``values``), with the
    clinic's ``cause`` and ``action`` in plain words (both ``""`` for a note only an engineer reads; an invalid
    finding without its own action: ``repeat the session``, as the report says)."""
    spec = finding.spec
    cause = spec.cause.format(where=finding.where.replace("_", " ")) if spec.cause else ""
    action = spec.action or ("repeat the session" if cause and finding.severity is Severity.INVALID else "")
    return {**finding.to_json(), "cause": cause, "action": action}


def record_to_json(record: SessionRecord) -> dict[str, Any]:
    """``record`` as a JSON-ready dict (the estimate layout plus the session block); each finding with the clinic's
    cause and action (:func:`finding_to_json`)."""
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
            "message": record.quality.message,
            "findings": [finding_to_json(f) for f in record.quality.findings],
        },
        "session": {
            "subject": record.subject,
            "number": record.number,
            "start_time_ns": record.session_time_ns,
            "source": record.source,
            "method": record.method,
            "config": record.config,
            "arm": record.arm,
            "retest": record.retest,
            "cell": record.cell,
        },
        "subject": record.subject_info,
    }
    if record.repeatability:
        body["repeatability"] = record.repeatability
    from bsp_ros.clinic.store.curves import CURVE_KEY, angle_of

    for (group, part, quantity), q in record.parameters.items():
        if group == "joints" and part in record.passive_curves and angle_of(quantity) is not None:
            continue  # sampled from the curve, which is given whole
        body[group].setdefault(part, {})[quantity] = q.to_json()
    for joint, curve in record.passive_curves.items():
        body["joints"].setdefault(joint, {})[CURVE_KEY] = curve
    return body
