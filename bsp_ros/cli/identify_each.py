"""`bsp identify --each BAG...`: every bag its own session, one estimate JSON per bag and a summary CSV row per bag.

The bags run in this process (``--jobs 1``) or in worker processes, one bag at a time each, so memory is bounded
by the number of workers. Each bag's row carries the exit code `bsp identify BAG` alone would give; a bag that
fails has its row and the others go on.

Kept light at import (no numpy), as every module `bsp` loads to build its parser.
"""

from __future__ import annotations

import argparse
import csv
import os
import signal
import sys
from collections import deque
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from bsp_ros.bag.batch import bag_name, expand_bags
from bsp_ros.cli.identify import BAG_EXIT_CODES, DATA_PROBLEMS, EXIT_INVALID
from bsp_ros.core.estimate_blocks import TareBlock, typed_block
from bsp_ros.core.findings import findings_of, plain_cause, verdict_of
from bsp_ros.core.quantities import quantities_of
from bsp_ros.errors import BspError, DataError, InputError

#: Segment quantities the summary carries (with their std): what gravity identifies and the mass it implies.
SEGMENT_KEYS = ("static_moment_kgm", "mass_kg")
#: The summary's columns before the parameters and after them; the parameters' columns are those the bags have.
HEAD_COLUMNS = ("bag", "exit_code", "valid", "cause_code", "cause")
TAIL_COLUMNS = ("tare_applied", "passive_model", "duration_s", "content_sha256", "json")
# What a bag whose worker process died gets (killed by the system, out of memory): as a crashed `bsp identify`.
EXIT_WORKER_DIED = 1


@dataclass(frozen=True)
class BagTask:
    """One bag to identify in a worker: what it needs, small enough to send to another process.

    Attributes
    ----------
    index : the bag's position among the inputs (0-based).
    bag : the bag's path as given.
    json_path : where its estimate JSON goes.
    options : the ``IdentifyOptions`` of the command line.
    topics : the ``TopicMap`` of the command line.
    tilts_rad : the trunk's tilt (rad) as a one-element list, or None.
    """

    index: int
    bag: str
    json_path: str
    options: Any
    topics: Any
    tilts_rad: list[float] | None


@dataclass(kw_only=True)
class BagRow:
    """What one bag gave: its summary row before the columns are known.

    Attributes
    ----------
    index, bag : as in :class:`BagTask`.
    exit_code : what `bsp identify BAG` alone would exit with.
    valid : the estimate's verdict; None without an estimate.
    cause_code, cause : for an invalid estimate its first invalid finding's code and plain cause; for a bag that
        failed, ``""`` and the error's line.
    values : column (``<quantity>/<owner>`` and ``<quantity>/<owner>_std``) -> value in the quantity's unit.
    tare_applied : whether a tare was subtracted; None without an estimate.
    passive_model : the passive model used (``diagnostics.passive_model``, else the configured one).
    duration_s : the session's duration (s); None without an estimate.
    content_sha256 : the bag's content hash (as the session store keys it), ``""`` without an estimate.
    json : the estimate file's name in the JSON directory, ``""`` if none was written.
    """

    index: int
    bag: str
    exit_code: int
    valid: bool | None = None
    cause_code: str = ""
    cause: str = ""
    values: dict[str, float | None] = field(default_factory=dict)
    tare_applied: bool | None = None
    passive_model: str = ""
    duration_s: float | None = None
    content_sha256: str = ""
    json: str = ""


def identify_one(task: BagTask) -> BagRow:
    """Identify one bag, write its estimate JSON, and return its row (never raises for a bag's failure).

    An estimate is written whatever its verdict (also one whose data are too few, exit 3), so its reasons can be
    read; a bag that cannot be read or identified has a row and no file. An unexpected error (a defect) is the
    bag's row too, so one bag never stops the others.
    """
    from bsp_ros.bag.offline import identify_bags
    from bsp_ros.errors import BagError

    try:
        document = identify_bags([Path(task.bag)], task.options, task.topics, None, task.tilts_rad)
    except BagError as error:
        code = BAG_EXIT_CODES.get(getattr(error, "code", ""), error.exit_code)
        return BagRow(index=task.index, bag=task.bag, exit_code=code, cause=_one_line(error))
    except BspError as error:
        return BagRow(index=task.index, bag=task.bag, exit_code=error.exit_code, cause=_one_line(error))
    except Exception as error:  # a defect on one bag: said in its row, the batch goes on
        return BagRow(
            index=task.index,
            bag=task.bag,
            exit_code=1,
            cause=f"internal error: {type(error).__name__}: {_one_line(error)}",
        )
    row = row_of(task.index, task.bag, document)
    try:
        _write_json(Path(task.json_path), document)
    except OSError as error:
        row.exit_code, row.cause_code = InputError.exit_code, ""
        row.cause = f"cannot write {task.json_path} ({error.strerror})"
        return row
    row.json = Path(task.json_path).name
    return row


def row_of(index: int, bag: str, document: dict[str, Any]) -> BagRow:
    """The summary row of a bag's estimate ``document``: its verdict, exit code and parameters."""
    quality = document["quality"]
    findings = findings_of(quality)
    invalid = verdict_of(findings)
    if quality["valid"]:
        code = 0
    elif any(f.code in DATA_PROBLEMS for f in findings):
        code = DataError.exit_code
    else:
        code = EXIT_INVALID
    row = BagRow(index=index, bag=bag, exit_code=code, valid=bool(quality["valid"]))
    if not quality["valid"]:
        if invalid is not None:
            plain = plain_cause([invalid])
            row.cause_code, row.cause = str(invalid.code), plain[0] if plain else invalid.text
        else:  # a document without findings (an older writer): its message says why
            row.cause = _one_line(quality.get("message", ""))
    row.values = parameter_values(document)
    tare = typed_block(TareBlock.from_json, quality.get("tare"))
    row.tare_applied = tare is not None and tare.applied
    session = document.get("session") or {}
    configured = (session.get("config") or {}).get("passive", "")
    row.passive_model = str((document.get("diagnostics") or {}).get("passive_model") or configured)
    row.duration_s = session.get("duration_s")
    row.content_sha256 = str(session.get("content_sha256", ""))
    return row


def parameter_values(document: dict[str, Any]) -> dict[str, float | None]:
    """Each segment's static moment and mass and each joint's passive parameters, with their std, by column name
    (``static_moment_kgm/forearm``, ``static_moment_kgm/forearm_std``), in the document's units."""
    out: dict[str, float | None] = {}
    for group, owner, key, q in quantities_of(document):
        if group == "segments" and key not in SEGMENT_KEYS:
            continue
        out[f"{key}/{owner}"] = q["value"]
        out[f"{key}/{owner}_std"] = q["std"]
    return out


def value_columns(rows: Iterable[BagRow]) -> list[str]:
    """The parameter columns of ``rows``: segments first (static moments, then masses), then the joints' passive
    parameters, each kind's owners in the order the bags give them."""
    seen: dict[str, None] = {}
    for row in rows:
        seen.update(dict.fromkeys(row.values))

    def kind(column: str) -> tuple[int, str]:
        quantity = column.split("/", 1)[0]
        return (SEGMENT_KEYS.index(quantity) if quantity in SEGMENT_KEYS else len(SEGMENT_KEYS), quantity)

    order = {column: k for k, column in enumerate(seen)}
    kinds: dict[str, int] = {}
    for column in seen:  # a joint quantity ranks where it first appears, so its owners stay together
        kinds.setdefault(kind(column)[1], len(kinds))
    return sorted(seen, key=lambda c: (kind(c)[0], kinds[kind(c)[1]], order[c]))


def write_summary(rows: Sequence[BagRow], stream: TextIO) -> list[str]:
    """Write ``rows`` (sorted by input order) as CSV with a header; return the header.

    Numbers are written with ``repr`` so they read back to the same float as in the JSON; a missing value is an
    empty cell; ``valid`` and ``tare_applied`` are 1 or 0 (empty without an estimate).
    """
    columns = [*HEAD_COLUMNS, *value_columns(rows), *TAIL_COLUMNS]
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow(columns)
    for row in sorted(rows, key=lambda r: r.index):
        cells: dict[str, Any] = {
            "bag": row.bag,
            "exit_code": row.exit_code,
            "valid": _flag(row.valid),
            "cause_code": row.cause_code,
            "cause": row.cause,
            "tare_applied": _flag(row.tare_applied),
            "passive_model": row.passive_model,
            "duration_s": _number(row.duration_s),
            "content_sha256": row.content_sha256,
            "json": row.json,
        }
        cells.update({column: _number(value) for column, value in row.values.items()})
        writer.writerow([cells.get(column, "") for column in columns])
    return columns


def _flag(value: bool | None) -> str:
    return "" if value is None else str(int(value))


def _number(value: float | None) -> str:
    return "" if value is None else repr(float(value))


def _one_line(error: BaseException | str) -> str:
    return " ".join(str(error).split())


def _write_json(path: Path, document: dict[str, Any]) -> None:
    """``document`` as `bsp identify --json` writes it, replaced in one step (no half-written file is left)."""
    import json

    text = json.dumps(document, indent=2, allow_nan=False) + "\n"
    partial = path.with_name(f".{path.name}.partial")
    partial.write_text(text)
    os.replace(partial, path)


def _worker_start() -> None:
    """A worker's start: Ctrl-C is the main process's to handle; freed arrays are reused as in `bsp identify`.

    BLAS keeps its threads as in `bsp identify`: their number changes the last digits of a sum, and a bag's row
    should not depend on ``--jobs`` (``OPENBLAS_NUM_THREADS=1`` in the environment gives each worker one thread).
    """
    from bsp_ros.allocator import reuse_freed_memory

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    reuse_freed_memory()


def run_tasks(tasks: Sequence[BagTask], jobs: int, done: Callable[[BagRow], None]) -> None:
    """Identify ``tasks``: here for one job, else in ``jobs`` worker processes; ``done`` gets each row as it
    finishes. A worker that dies (killed, out of memory) costs only its own bag: the bags running then are
    retried one by one, each alone in a fresh worker, so the bag that kills its worker is the one that says so.
    """
    if jobs <= 1:
        for task in tasks:
            done(identify_one(task))
        return
    queue = deque(tasks)
    while queue:
        for task in _run_until_broken(queue, jobs, done):
            for lost in _run_until_broken(deque([task]), 1, done):
                done(
                    BagRow(
                        index=lost.index,
                        bag=lost.bag,
                        exit_code=EXIT_WORKER_DIED,
                        cause="the worker process died on this bag",
                    )
                )


def _run_until_broken(queue: deque[BagTask], jobs: int, done: Callable[[BagRow], None]) -> list[BagTask]:
    """Run ``queue``'s tasks in a pool of ``jobs`` workers, at most ``jobs`` at a time, until it is empty or the
    pool breaks; return the tasks that were running when it broke (none if it did not)."""
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    # forkserver (spawn where there is none): a fork of this process would copy its state and its threads.
    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
    pool = ProcessPoolExecutor(jobs, mp_context=context, initializer=_worker_start)
    running: dict[Future[BagRow], BagTask] = {}
    lost: list[BagTask] = []
    try:
        while (queue or running) and not lost:
            while queue and len(running) < jobs:
                task = queue.popleft()
                running[pool.submit(identify_one, task)] = task
            finished, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in finished:
                task = running.pop(future)
                try:
                    done(future.result())
                except BrokenProcessPool:
                    lost.append(task)
    except BaseException:  # Ctrl-C: stop now, not after the bags still running
        _stop(pool)
        raise
    if lost:  # the pool broke: the others running then are lost with it
        _stop(pool)
        return sorted([*lost, *running.values()], key=lambda t: t.index)
    pool.shutdown(wait=True)
    return []


def _stop(pool: Any) -> None:
    """Shut ``pool`` down without waiting for bags still running (on Ctrl-C or a broken pool): its workers are
    this command's own processes, ended by their ids."""
    pool.shutdown(wait=False, cancel_futures=True)
    for process in list((getattr(pool, "_processes", None) or {}).values()):  # not public; absent: leave them
        if process.is_alive():
            process.terminate()
    pool.shutdown(wait=True)


def check_each_args(args: argparse.Namespace) -> None:
    """Refuse (exit 2) the options that do not go with ``--each`` or that it needs; the batch options without it."""
    given = [name for name in ("json_dir", "summary", "jobs") if getattr(args, name) is not None]
    if not args.each:
        if given:
            raise InputError(f"--{given[0].replace('_', '-')} goes with --each (every bag its own session)")
        return
    if args.json is not None:
        raise InputError("--json is one estimate: with --each give --json-dir DIR (one <bag name>.json per bag)")
    for name in ("json_dir", "summary"):
        if getattr(args, name) is None:
            raise InputError(f"--each needs --{name.replace('_', '-')}")
    if args.format in ("table", "tsv"):
        raise InputError(f"--format {args.format} is one estimate's output: with --each the rows are in --summary")
    if args.trunk_tilt_deg is not None and len(args.trunk_tilt_deg) != 1:
        raise InputError(f"--trunk-tilt-deg with --each takes one tilt for every bag, got {len(args.trunk_tilt_deg)}")


def plan_tasks(args: argparse.Namespace, json_dir: Path) -> list[BagTask]:
    """One task per bag of the command line (folders of bags expanded); two bags of one name are refused, as
    their JSON files would be one."""
    from bsp_ros.cli.identify_options import options_from_args, topics_from_args, trunk_tilts_rad

    bags = expand_bags(args.bag)
    by_name: dict[str, Path] = {}
    for bag in bags:
        name = bag_name(bag)
        if name in by_name:
            raise InputError(f"two bags named {name} ({by_name[name]}, {bag}) would both write {json_dir / name}.json")
        by_name[name] = bag
    options, topics = options_from_args(args), topics_from_args(args)
    tilts = trunk_tilts_rad(args.trunk_tilt_deg, 1)
    return [
        BagTask(k, str(bag), str(json_dir / f"{bag_name(bag)}.json"), options, topics, tilts)
        for k, bag in enumerate(bags)
    ]


class Progress:
    """A line on stderr, rewritten as bags finish, when stderr is a terminal (else silent)."""

    def __init__(self, total: int, stream: TextIO | None = None) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.show = self.stream.isatty()
        self.total, self.count, self.not_valid = total, 0, 0

    def __call__(self, row: BagRow) -> None:
        """Count ``row`` and redraw the line."""
        self.count += 1
        self.not_valid += row.exit_code != 0
        if self.show:
            end = "\n" if self.count >= self.total else ""
            line = f"\ridentify --each: {self.count}/{self.total} bags, {self.not_valid} not valid"
            self.stream.write(line + end)
            self.stream.flush()


def run_each(args: argparse.Namespace) -> int:
    """`bsp identify --each`: identify every bag alone, write the JSONs and the summary; 0 if all are valid."""
    from bsp_ros.validation import check_output_dir, check_output_file

    check_each_args(args)
    json_dir = check_output_dir("--json-dir", args.json_dir)
    to_stdout = str(args.summary) == "-"
    summary = None if to_stdout else check_output_file("--summary", args.summary)
    tasks = plan_tasks(args, json_dir)
    json_dir.mkdir(parents=True, exist_ok=True)
    rows: list[BagRow] = []
    progress = Progress(len(tasks))

    def done(row: BagRow) -> None:
        rows.append(row)
        progress(row)

    try:
        run_tasks(tasks, min(args.jobs or 1, len(tasks)), done)
    finally:  # also on Ctrl-C: the bags finished so far keep their rows
        _write_summary_file(rows, summary)
    if to_stdout:
        write_summary(rows, sys.stdout)
    elif args.format != "none":
        valid = sum(row.exit_code == 0 for row in rows)
        print(f"wrote {len(rows)} rows ({valid} valid, {len(rows) - valid} not) to {summary}")
    return 0 if all(row.exit_code == 0 for row in rows) else EXIT_INVALID


def _write_summary_file(rows: Sequence[BagRow], summary: Path | None) -> None:
    if summary is None:
        return
    # A regular file is replaced in one step (a reader never sees half of it); a device or pipe is written to.
    regular = not summary.exists() or summary.is_file()
    target = summary.with_name(f".{summary.name}.partial") if regular else summary
    try:
        summary.parent.mkdir(parents=True, exist_ok=True)
        with open(target, "w", newline="", encoding="utf-8") as stream:
            write_summary(rows, stream)
        if regular:
            os.replace(target, summary)
    except OSError as error:  # checked before the bags ran: a disk that filled or changed since
        raise InputError(f"--summary {summary}: cannot write ({error.strerror})") from None
