"""A finished session's bag identified as `bsp sessions add BAG` identifies one, and stored for its subject.

Runs on a worker thread of `session_recorder` (a whole session takes seconds to identify); everything here is
plain Python on files and the store, and returns a :class:`SessionOutcome` for the node to log.
"""

from __future__ import annotations

import argparse
import shlex
import shutil
from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from bsp_ros.bag import TopicMap
from bsp_ros.cell import CellDescription
from bsp_ros.clinic.store import WALL_CLOCK_START_NS, open_store
from bsp_ros.core.methods import Method
from bsp_ros.errors import BspError
from bsp_ros.live.session.control import SessionEnd
from bsp_ros.live.session.spool import SpoolSummary

__all__ = [
    "IdentifySettings",
    "OutcomeKind",
    "SessionJob",
    "SessionOutcome",
    "add_command",
    "add_options_for",
    "cell_file_for",
    "store_session",
]


@dataclass(frozen=True, kw_only=True)
class IdentifySettings:
    """The `bsp identify` options a recorded session is identified with (the subject's body data come from the
    store's subject record).

    Attributes
    ----------
    method : ``joint`` or ``paper``.
    passive : passive model (``--passive``); empty: the default (Coulomb, and auto where the data demand it).
    tare_file : tare file of `bsp tare` (empty: none).
    wrench_delay_s : the wrench delay the cell knows, s (None: estimated from the data).
    marker_placement_sd_mm, handle_pose_sd_mm : the placement terms of every std, mm.
    topics : the session's topic names.
    cell_file : the cell description the session is identified with (`bsp identify --cell`: its transform topic,
        and its mounting where the bag records no transform); '' none.
    """

    method: Method = Method.JOINT
    passive: str = ""
    tare_file: str = ""
    wrench_delay_s: float | None = None
    marker_placement_sd_mm: float = 2.0
    handle_pose_sd_mm: float = 0.5
    topics: TopicMap = field(default_factory=TopicMap)
    cell_file: str = ""

    def command_line(self) -> list[str]:
        """These settings as `bsp identify` / `bsp sessions add` options."""
        line = ["--method", str(self.method), "--wrench-topic", self.topics.wrench]
        line += ["--tf-topic", self.topics.tf, "--tf-static-topic", self.topics.tf_static]
        line += ["--handle-pose-topic", self.topics.handle_pose]
        line += [f"--marker-topic={name}={topic}" for name, topic in self.topics.markers.items()]
        line += ["--marker-placement-sd-mm", repr(self.marker_placement_sd_mm)]
        line += ["--handle-pose-sd-mm", repr(self.handle_pose_sd_mm)]
        if self.passive:
            line += ["--passive", self.passive]
        if self.tare_file:
            line += ["--tare", self.tare_file]
        if self.wrench_delay_s is not None:
            line += ["--wrench-delay-s", repr(self.wrench_delay_s)]
        if self.cell_file:
            line += ["--cell", self.cell_file]
        return line

    def add_options(self) -> list[str]:
        """These settings as `bsp sessions add` options (its ``--cell`` names the cell the session was recorded in,
        so the cell description is ``--cell-file``)."""
        return ["--cell-file" if word == "--cell" else word for word in self.command_line()]

    def arguments(self) -> argparse.Namespace:
        """The parsed options, as `bsp sessions add` parses its command line (same defaults and checks).

        Raises
        ------
        InputError
            A value the command line would refuse (naming the option).
        """
        from bsp_ros.cli.identify_options import add_identify_arguments
        from bsp_ros.errors import InputError

        parser = argparse.ArgumentParser(prog="session_recorder", add_help=False, exit_on_error=False)
        add_identify_arguments(parser)
        try:
            args, extra = parser.parse_known_args(self.command_line())
        except (argparse.ArgumentError, SystemExit) as error:
            raise InputError(f"identification settings: {error}") from None
        if extra:
            raise InputError(f"identification settings: not understood: {' '.join(extra)}")
        args.trunk_tilt_deg = None
        return args

    def check(self) -> None:
        """Refuse settings that would fail every session (a bad passive model, a missing tare file) at start.

        Raises
        ------
        InputError
            Naming the option and value.
        """
        from bsp_ros.cli.identify_options import options_from_args

        options_from_args(self.arguments())


@dataclass(frozen=True, kw_only=True)
class SessionJob:
    """A finished session to identify and store.

    Attributes
    ----------
    ended : the session (subject, retest) and how it ended.
    spool : its bag, complete.
    store_location : the store (None: the per-user default).
    settings : how to identify it.
    cell : the robot cell's name stored with the session (None: not recorded).
    keep_recording : keep the bag of a valid stored session too (it is always kept otherwise).
    """

    ended: SessionEnd
    spool: SpoolSummary
    store_location: str | None
    settings: IdentifySettings
    cell: str | None = None
    keep_recording: bool = False


class OutcomeKind(StrEnum):
    """What became of a finished session."""

    STORED = "stored"  # identified and stored (valid or not)
    EMPTY = "empty"  # no wrench arrived: nothing to identify, no bag left
    FAILED = "failed"  # not stored: the bag is kept and the outcome says why


@dataclass(frozen=True, kw_only=True)
class SessionOutcome:
    """A finished session's fate, for the log.

    Attributes
    ----------
    kind : stored, empty or failed.
    subject, retest : whose session, and whether a same-day retest.
    store : the store's location (password redacted).
    recorded_s : the receive span of the session's messages, s.
    estimate_s : the span of the samples the estimate was made from, s (None: no estimate).
    number : the session's number for its subject (None: not stored).
    arm : the arm stored (the subject record's), or None.
    valid : the estimate's verdict (None: not stored).
    cause : why it is not valid, or why it failed.
    kept : the bag, where it is kept (None: removed).
    """

    kind: OutcomeKind
    subject: str
    retest: bool
    store: str
    recorded_s: float
    estimate_s: float | None = None
    number: int | None = None
    arm: str | None = None
    valid: bool | None = None
    cause: str | None = None
    kept: Path | None = None
    add_options: tuple[str, ...] = ()

    def log_line(self) -> str:
        """One line: what was stored where, or why nothing was and where the data are."""
        if self.kind is OutcomeKind.EMPTY:
            return f"session of {self.subject} ended without a wrench message: nothing to store"
        if self.kind is OutcomeKind.FAILED:
            assert self.kept is not None
            command = add_command(self.kept, self.subject, self.retest, self.add_options)
            return (
                f"session of {self.subject} ({self.recorded_s:.1f} s) NOT stored: {self.cause}; its recording is "
                f"kept at {self.kept}: add it with `{command}`"
            )
        marks = [f"{self.arm} arm" if self.arm else "", "retest" if self.retest else ""]
        what = ", ".join(m for m in (*marks, f"{self.estimate_s or 0.0:.1f} s") if m)
        verdict = "valid" if self.valid else f"NOT VALID: {self.cause}"
        line = f"stored session {self.number} of {self.subject} ({what}, {verdict}) into {self.store}"
        return line if self.kept is None else f"{line}; its recording is kept at {self.kept}"


def cell_file_for(cell: CellDescription, rotation_xyzw: Sequence[float], tare_file: str) -> str:
    """The cell file a recorded session is identified with (:attr:`IdentifySettings.cell_file`): the recorder's, so
    that its TransformStamped topic is read; '' where the recorder's parameters override the cell's mounting or tare
    (``--cell`` would bring the cell's back; the bag's metadata states the parameter's mounting)."""
    same_mounting = np.allclose(np.asarray(rotation_xyzw, dtype=np.float64), cell.rotation_xyzw, atol=1e-9)
    cell_tare = "" if cell.tare_file is None else str(cell.tare_file)
    return cell.source if same_mounting and tare_file == cell_tare else ""


def add_command(path: Path, subject: str, retest: bool, options: Sequence[str] = ()) -> str:
    """The `bsp sessions add` command that stores a kept recording by hand, as the recorder would have: ``options``
    the session's own (:func:`add_options_for`: its topics, tare, cell file and cell), quoted for a shell."""
    words = ["bsp", "sessions", "add", str(path), "--subject", subject, *(["--retest"] if retest else []), *options]
    return shlex.join(words)


def add_options_for(settings: IdentifySettings, cell: str | None) -> tuple[str, ...]:
    """A session's identification ``settings`` and ``cell`` (its name, or None) as `bsp sessions add` options."""
    return (*settings.add_options(), *(["--cell", cell] if cell else []))


def _span_s(estimate: dict[str, Any]) -> float | None:
    session = estimate.get("session")
    start, end = (session.get("start_time_ns"), session.get("end_time_ns")) if isinstance(session, dict) else (0, 0)
    if isinstance(start, int) and isinstance(end, int) and end >= start:
        return (end - start) / 1e9
    return None


def _identify_and_store(job: SessionJob) -> SessionOutcome:
    """Identify the bag with the subject record's body data and store it; BspError where that fails."""
    from bsp_ros.cli.session_actions import identify_bag_for_store, verdict_text

    ended, spool = job.ended, job.spool
    subject = ended.session.subject
    with open_store(job.store_location) as store:
        known = store.subject_record(subject)
        body = known.body() if known is not None else {}
        estimate = identify_bag_for_store(spool.path, job.settings.arguments(), body)
        stamped = estimate.get("session", {}).get("start_time_ns")
        # Stamps on a controller's boot clock are no session time: the first receive time (wall clock) is.
        wall_clock = isinstance(stamped, int) and stamped >= WALL_CLOCK_START_NS
        record = store.add_estimate(
            estimate,
            subject,
            session_time_ns=None if wall_clock else spool.first_ns,
            source=spool.path.name,
            retest=True if ended.session.retest else None,
            cell=job.cell,
        )
        location = store.location
    valid = record.quality.valid
    keep = job.keep_recording or not valid
    if not keep:
        shutil.rmtree(spool.path, ignore_errors=True)
    return SessionOutcome(
        kind=OutcomeKind.STORED,
        subject=subject,
        retest=record.retest,
        store=location,
        recorded_s=spool.duration_s,
        estimate_s=_span_s(estimate),
        number=record.number,
        arm=record.arm,
        valid=valid,
        cause=None if valid else verdict_text(record.quality),
        kept=spool.path if keep else None,
    )


def store_session(job: SessionJob, store_name: str) -> SessionOutcome:
    """Identify and store a finished session; never raises for a session that cannot be stored.

    Parameters
    ----------
    job : the session and its bag.
    store_name : the store's location as the log names it (where a failure stops before the store is open).

    Returns
    -------
    SessionOutcome
        Stored (the bag removed unless kept or not valid), empty (no wrench: the bag removed), or failed (the
        bag kept, the cause said).
    """
    ended, spool = job.ended, job.spool
    subject, retest = ended.session.subject, ended.session.retest
    if not spool.counts.get(job.settings.topics.wrench):
        shutil.rmtree(spool.path, ignore_errors=True)
        return SessionOutcome(
            kind=OutcomeKind.EMPTY, subject=subject, retest=retest, store=store_name, recorded_s=spool.duration_s
        )
    try:
        return _identify_and_store(job)
    except Exception as error:  # whatever fails, the session's recording stays and the log says where
        cause = str(error) if isinstance(error, BspError) else f"unexpected error {error!r}"
        return SessionOutcome(
            kind=OutcomeKind.FAILED,
            subject=subject,
            retest=retest,
            store=store_name,
            recorded_s=spool.duration_s,
            cause=cause,
            kept=spool.path,
            add_options=add_options_for(job.settings, job.cell),
        )
