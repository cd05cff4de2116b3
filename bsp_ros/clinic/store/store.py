"""The session store: one row per identification session, parameters stored generically."""

from __future__ import annotations

import json
import os
import time
from collections.abc import Mapping
from dataclasses import replace
from types import TracebackType
from typing import Any

from bsp_ros.clinic.store.backends import Backend, connect
from bsp_ros.clinic.store.estimate import check_future, parse_estimate, record_from_estimate
from bsp_ros.clinic.store.location import default_location, is_database_url
from bsp_ros.clinic.store.records import (
    AFFECTED,
    ARMS,
    ParamKey,
    Quality,
    Quantity,
    SessionRecord,
    SubjectRecord,
    SubjectSummary,
    format_time,
)
from bsp_ros.clinic.store.schema import APPLICATION, SCHEMA_VERSION, migration_statements
from bsp_ros.clinic.store.subject import check_subject_id
from bsp_ros.core.estimate_schema import Estimate, Source
from bsp_ros.core.findings import findings_of
from bsp_ros.errors import InputError, StoreError

_MIGRATION_LOCK = 0x6273_7073  # PostgreSQL advisory lock key ("bsps") serialising migrations
_SESSION_COLUMNS = (
    "id, subject, session_time_ns, source, method, config_json, subject_info_json, estimate_schema, "
    "valid, n_samples, condition_number, quality_json, added_ns, repeatability_json, arm, retest, cell, "
    "content_sha256, curves_json, passive_model"
)
_DAY_NS = 86_400 * 10**9


class Store:
    """An open session store.

    Use :func:`open_store` to get one; it is a context manager that closes the connection.
    Every method that changes the store returns only after the change is committed.
    """

    def __init__(self, backend: Backend) -> None:
        self._backend = backend
        try:
            self.schema_version = self._migrate()
        except BaseException:
            backend.close()
            raise

    @property
    def location(self) -> str:
        """The store's file path or database URL (password redacted)."""
        return self._backend.location

    @property
    def dialect(self) -> str:
        """``sqlite`` or ``postgresql``."""
        return self._backend.dialect

    def __enter__(self) -> Store:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, error: BaseException | None, trace: TracebackType | None
    ) -> None:
        self.close()

    def close(self) -> None:
        """Close the connection."""
        self._backend.close()

    def add_estimate(
        self,
        estimate: Estimate | Mapping[str, Any],
        subject: str,
        *,
        session_time_ns: int | None = None,
        source: str | None = None,
        arm: str | None = None,
        retest: bool | None = None,
        cell: str | None = None,
    ) -> SessionRecord:
        """Store an estimate as a session of ``subject``: a typed one, or its JSON checked first.

        Parameters
        ----------
        estimate : Estimate or Mapping
            The typed estimate (:func:`bsp_ros.clinic.store.estimate.record_from_estimate`), or its
            `bsp_ros/core/estimate/1` JSON as read (:func:`bsp_ros.clinic.store.estimate.parse_estimate`).
        subject : str
            Pseudonymous subject id.
        session_time_ns : int, optional
            Session start; overrides the estimate's ``session.start_time_ns``.
        source : str, optional
            Recording name; overrides the estimate's ``session.source``.
        arm, retest, cell : optional
            The measured arm (default: the subject record's), a same-day retest, the robot cell.

        Returns
        -------
        SessionRecord
            The stored session, with its ``id``; returned only after the commit.
        """
        facts: dict[str, Any] = {"session_time_ns": session_time_ns, "source": source, "arm": arm}
        facts.update(retest=retest, cell=cell)
        if isinstance(estimate, Estimate):
            return self.add(record_from_estimate(estimate, subject, **facts))
        return self.add(parse_estimate(estimate, subject, **facts))

    def add(self, record: SessionRecord) -> SessionRecord:
        """Store one session; return it with ``id`` and ``added_ns`` set, after the commit.

        The arm defaults to the subject record's. The session keeps its own body data, those its prior was made
        with (an estimate made without them carries the population default): writing the record's over them would
        label masses with a prior they were not computed from (see :meth:`SubjectRecord.differs_from`).

        Raises
        ------
        StoreError
            If the subject already has a session with the same time and source, or the same recording
            (content hash) is stored already.
        InputError
            If the session lies in the future, or is a retest without the same day's session before it.
        """
        check_subject_id(record.subject)
        added_ns = time.time_ns()
        check_future(record.session_time_ns, added_ns)
        known = self.subject_record(record.subject)
        if known is not None:
            record = replace(record, arm=record.arm or known.arm)
        row = _session_row(record, added_ns)
        duplicate = StoreError(
            f"duplicate session: subject {record.subject} already has a session at "
            f"{format_time(record.session_time_ns)} from {record.source!r}; nothing was added"
        )
        try:
            with self._backend.transaction():
                if self._backend.query(
                    "SELECT id FROM sessions WHERE subject = ? AND session_time_ns = ? AND source = ?",
                    (record.subject, record.session_time_ns, record.source),
                ):
                    raise duplicate
                self.refuse_stored_content(record.content_sha256)
                if record.retest:
                    self._check_retest(record)
                session_id = self._insert_session(row, record.parameters)
        except Exception as error:
            if self._backend.is_integrity_error(error):
                raise duplicate from None
            raise
        number = self._number_of(record.subject, session_id)
        return replace(record, id=session_id, added_ns=added_ns, number=number)

    def _insert_session(self, row: tuple[Any, ...], parameters: Mapping[ParamKey, Quantity]) -> int:
        """Insert a session's row (:func:`_session_row`) and its parameters' rows; return the session's id.

        Call it inside a transaction: a failure part way leaves nothing once the transaction rolls back.
        """
        rows = self._backend.query(_INSERT_SESSION_SQL, row)
        session_id = int(rows[0][0])
        for (group, part, quantity), q in parameters.items():
            budget = None if q.budget is None else _dumps(dict(q.budget))
            values = (session_id, group, part, quantity, q.value, q.std, str(q.source), budget)
            self._backend.query(_INSERT_PARAMETER_SQL, values)
        return session_id

    def refuse_stored_content(self, content_sha256: str | None) -> None:
        """StoreError naming the session if a recording with this content hash is stored (None: no check)."""
        if content_sha256 is None:
            return
        rows = self._backend.query(
            "SELECT id, subject, session_time_ns FROM sessions WHERE content_sha256 = ?", (content_sha256,)
        )
        if rows:
            sid, subject, time_ns = rows[0]
            number = self._number_of(str(subject), int(sid))
            raise StoreError(
                f"duplicate recording: the same recording is already stored as session {number} of {subject} "
                f"({format_time(int(time_ns))}); nothing was added"
            )

    def _check_retest(self, record: SessionRecord) -> None:
        day = record.session_time_ns - record.session_time_ns % _DAY_NS
        arm_sql, arm_params = ("arm IS NULL", ()) if record.arm is None else ("arm = ?", (record.arm,))
        rows = self._backend.query(
            f"SELECT COUNT(*) FROM sessions WHERE subject = ? AND retest = 0 AND {arm_sql} "
            "AND session_time_ns >= ? AND session_time_ns <= ?",
            (record.subject, *arm_params, day, record.session_time_ns),
        )
        if not int(rows[0][0]):
            arm = f" of the {record.arm} arm" if record.arm else ""
            raise InputError(
                f"a retest is the second session of a day: {record.subject} has no session{arm} earlier on "
                f"{format_time(record.session_time_ns)[:10]} to pair it with; add that session first (without "
                "--retest), or drop --retest"
            )

    def _number_of(self, subject: str, session_id: int) -> int:
        ids = [int(r[0]) for r in self._backend.query(_NUMBERING_SQL, (subject,))]
        return ids.index(session_id) + 1

    def set_subject(self, update: SubjectRecord) -> SubjectRecord:
        """Store the subject record, keeping fields of an earlier record that ``update`` leaves None.

        Returns
        -------
        SubjectRecord
            The record as stored.
        """
        check_subject_id(update.subject)
        if update.arm is not None and update.arm not in ARMS:
            raise InputError(f"arm must be one of {ARMS}, got {update.arm!r}")
        if update.affected is not None and update.affected not in AFFECTED:
            raise InputError(f"affected arm must be one of {AFFECTED}, got {update.affected!r}")
        old = self.subject_record(update.subject) or SubjectRecord(update.subject)
        merged = SubjectRecord(
            update.subject,
            *(new if new is not None else was for new, was in zip(_fields(update), _fields(old), strict=True)),
        )
        with self._backend.transaction():
            self._backend.query("DELETE FROM subjects WHERE subject = ?", (merged.subject,))
            self._backend.query(
                "INSERT INTO subjects (subject, body_mass_kg, height_m, sex, arm, affected, updated_ns) "
                "VALUES (?, ?, ?, ?, ?, ?, ?)",
                (merged.subject, *_fields(merged), time.time_ns()),
            )
        return merged

    def subject_record(self, subject: str) -> SubjectRecord | None:
        """The subject record of ``subject``, or None if none was set."""
        rows = self._backend.query(
            "SELECT body_mass_kg, height_m, sex, arm, affected FROM subjects WHERE subject = ?",
            (check_subject_id(subject),),
        )
        if not rows:
            return None
        mass, height, sex, arm, affected = rows[0]
        return SubjectRecord(subject, _float(mass), _float(height), sex, arm, affected)

    def remove(self, subject: str, number: int) -> SessionRecord:
        """Delete session ``number`` (1 = the subject's first in time) of ``subject``; return what was removed.

        Raises
        ------
        StoreError
            If the subject has no such session.
        """
        records = self.sessions(subject)
        if not 1 <= number <= len(records):
            raise StoreError(
                f"{subject} has sessions 1 to {len(records)}, not {number}: see `bsp sessions show {subject}`"
            )
        target = records[number - 1]
        with self._backend.transaction():
            self._backend.query("DELETE FROM parameters WHERE session_id = ?", (target.id,))
            self._backend.query("DELETE FROM sessions WHERE id = ?", (target.id,))
        self._backend.purge_freed_space()
        return target

    def subjects(self) -> list[SubjectSummary]:
        """Every subject with stored sessions, sorted by id."""
        rows = self._backend.query(
            "SELECT subject, COUNT(*), MIN(session_time_ns), MAX(session_time_ns), "
            "SUM(CASE WHEN valid = 0 THEN 1 ELSE 0 END) FROM sessions GROUP BY subject ORDER BY subject"
        )
        return [SubjectSummary(str(s), int(n), int(a), int(b), int(bad or 0)) for s, n, a, b, bad in rows]

    def sessions(self, subject: str | None = None) -> list[SessionRecord]:
        """Stored sessions in time order: of ``subject``, or of everyone if None.

        Raises
        ------
        StoreError
            If ``subject`` is given and has no sessions.
        """
        where, params = ("", ()) if subject is None else ("WHERE subject = ?", (check_subject_id(subject),))
        rows = self._backend.query(
            f"SELECT {_SESSION_COLUMNS} FROM sessions {where} ORDER BY session_time_ns, id", params
        )
        if subject is not None and not rows:
            raise StoreError(f"unknown subject {subject}: the store {self.location} holds no sessions of it")
        inner = "SELECT id FROM sessions" + (f" {where}" if where else "")
        numbers: dict[int, int] = {}
        counters: dict[str, int] = {}
        for row in rows:
            counters[row[1]] = counters.get(row[1], 0) + 1
            numbers[int(row[0])] = counters[row[1]]
        parameters: dict[int, dict[ParamKey, Quantity]] = {int(row[0]): {} for row in rows}
        for sid, group, part, quantity, value, std, source, budget in self._backend.query(
            "SELECT session_id, grp, part, quantity, value, std, source, budget_json FROM parameters "
            f"WHERE session_id IN ({inner}) ORDER BY session_id, grp, part, quantity",
            params,
        ):
            parameters[int(sid)][(group, part, quantity)] = Quantity(
                value=_float(value),
                std=_float(std),
                source=Source(source),
                budget=None if budget is None else json.loads(budget),
            )
        return [replace(_record(row, parameters[int(row[0])]), number=numbers[int(row[0])]) for row in rows]

    def erase(self, subject: str) -> int:
        """Delete every session of ``subject`` and rewrite storage so no bytes of it remain.

        On SQLite the file is vacuumed (with ``secure_delete``) and the WAL checkpointed and truncated,
        so neither the database file nor its ``-wal`` file holds the subject's id or values afterwards.
        On PostgreSQL the tables are rewritten (``VACUUM FULL``); server WAL and backups are the operator's.

        Returns
        -------
        int
            The number of sessions erased.

        Raises
        ------
        StoreError
            If the subject has no sessions.
        """
        check_subject_id(subject)
        with self._backend.transaction():
            count = int(self._backend.query("SELECT COUNT(*) FROM sessions WHERE subject = ?", (subject,))[0][0])
            known = self._backend.query("SELECT COUNT(*) FROM subjects WHERE subject = ?", (subject,))[0][0]
            if count == 0 and not int(known):
                raise StoreError(f"unknown subject {subject}: the store {self.location} holds no sessions of it")
            self._backend.query("DELETE FROM subjects WHERE subject = ?", (subject,))
            self._backend.query(
                "DELETE FROM parameters WHERE session_id IN (SELECT id FROM sessions WHERE subject = ?)",
                (subject,),
            )
            self._backend.query("DELETE FROM sessions WHERE subject = ?", (subject,))
        self._backend.purge_freed_space()
        return count

    def compact(self) -> None:
        """Rewrite storage so that deleted rows leave no bytes (what :meth:`erase` does after deleting)."""
        self._backend.purge_freed_space()

    def _read_version(self) -> int:
        tables = self._backend.tables()
        if not tables:
            return 0
        if "bsp_meta" not in tables:
            raise StoreError(f"{self.location} is a database but not a bsp_ros session store; not touching it")
        meta: dict[str, str] = {str(k): str(v) for k, v in self._backend.query("SELECT key, value FROM bsp_meta")}
        if meta.get("application") != APPLICATION or not str(meta.get("schema_version", "")).isdigit():
            raise StoreError(f"{self.location} has a bsp_meta table but is not a bsp_ros session store")
        return int(meta["schema_version"])

    def _check_known(self, version: int) -> None:
        if version > SCHEMA_VERSION:
            raise StoreError(
                f"store {self.location} has schema version {version}, newer than this bsp_ros understands "
                f"({SCHEMA_VERSION}); upgrade bsp_ros to use it (the store was not changed)"
            )

    def _migrate(self) -> int:
        version = self._read_version()
        self._check_known(version)
        if version == SCHEMA_VERSION:
            return version
        with self._backend.transaction():
            if self._backend.dialect == "postgresql":
                self._backend.query("SELECT pg_advisory_xact_lock(?)", (_MIGRATION_LOCK,))
            version = self._read_version()  # another process may have migrated meanwhile
            self._check_known(version)
            for sql in migration_statements(self._backend.dialect, version):
                self._backend.query(sql)
            if version == 0:
                self._backend.query("INSERT INTO bsp_meta (key, value) VALUES ('application', ?)", (APPLICATION,))
                self._backend.query("INSERT INTO bsp_meta (key, value) VALUES ('schema_version', '0')")
            self._backend.query("UPDATE bsp_meta SET value = ? WHERE key = 'schema_version'", (str(SCHEMA_VERSION),))
        return SCHEMA_VERSION


def open_store(location: str | os.PathLike[str] | None = None, *, create: bool = True) -> Store:
    """Open (creating or migrating if needed) the store at ``location``.

    Parameters
    ----------
    location : str or PathLike, optional
        A SQLite file path or a ``postgresql://`` URL; None means :func:`default_location`.
    create : bool
        False for reading: a SQLite file that does not exist is refused instead of created (a mistyped
        path would otherwise show an empty store).

    Returns
    -------
    Store
        The open store; close it (or use it as a context manager) when done.

    Raises
    ------
    StoreError
        If the location is not a bsp_ros store, cannot be opened, or has a newer schema.
    """
    target = default_location() if location is None else os.fspath(location)
    if not create and not is_database_url(target) and not os.path.exists(os.path.expanduser(target)):
        where = "--store" if location is not None else "the default store ($BSP_STORE or ~/.local/share/bsp_ros)"
        raise StoreError(
            f"no store at {target}: nothing has been stored there yet (check {where}; `bsp sessions add` creates it)"
        )
    return Store(connect(target))


def _dumps(value: Any) -> str:
    return json.dumps(value, sort_keys=True, allow_nan=False, separators=(",", ":"))


def _float(value: Any) -> float | None:
    return None if value is None else float(value)


_NUMBERING_SQL = "SELECT id FROM sessions WHERE subject = ? ORDER BY session_time_ns, id"
_INSERT_SESSION_SQL = (
    "INSERT INTO sessions (subject, session_time_ns, source, method, config_json, "
    "subject_info_json, estimate_schema, valid, n_samples, condition_number, quality_json, "
    "added_ns, repeatability_json, arm, retest, cell, content_sha256, curves_json, passive_model) "
    "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) RETURNING id"
)
_INSERT_PARAMETER_SQL = (
    "INSERT INTO parameters (session_id, grp, part, quantity, value, std, source, budget_json) "
    "VALUES (?, ?, ?, ?, ?, ?, ?, ?)"
)


def _fields(record: SubjectRecord) -> tuple[Any, ...]:
    return (record.body_mass_kg, record.height_m, record.sex, record.arm, record.affected)


def _session_row(record: SessionRecord, added_ns: int) -> tuple[Any, ...]:
    """The sessions table's row of ``record`` in ``_INSERT_SESSION_SQL``'s column order (``_record`` reads it back).

    Parameters
    ----------
    record : the session.
    added_ns : when it is stored, ns since the epoch.

    Returns
    -------
    The row's values, the JSON columns (config, body data, quality, repeatability, passive curves) dumped.
    """
    quality: dict[str, Any] = {
        "residual_rms_nm": record.quality.residual_rms_nm,
        "warnings": list(record.quality.warnings),
        "tare": {"applied": record.quality.tare_applied, "file": record.quality.tare_file},
        "message": record.quality.message,
        "findings": [f.to_json() for f in record.quality.findings],
    }
    return (
        record.subject,
        record.session_time_ns,
        record.source,
        record.method,
        _dumps(record.config),
        _dumps(record.subject_info),
        record.estimate_schema,
        int(record.quality.valid),
        record.quality.n_samples,
        record.quality.condition_number,
        _dumps(quality),
        added_ns,
        _dumps(record.repeatability),
        record.arm,
        int(record.retest),
        record.cell,
        record.content_sha256,
        _dumps(record.passive_curves),
        record.passive_model,
    )


def _record(row: tuple[Any, ...], parameters: dict[ParamKey, Quantity]) -> SessionRecord:
    sid, subject, time_ns, source, method, config, info, schema, valid, n, cond, quality, added, repeat = row[:14]
    arm, retest, cell, content, curves, passive_model = row[14:]
    extra = json.loads(quality)
    tare = extra.get("tare") if isinstance(extra.get("tare"), dict) else {}
    return SessionRecord(
        subject=subject,
        session_time_ns=int(time_ns),
        source=source,
        method=method,
        config=json.loads(config),
        subject_info=json.loads(info),
        estimate_schema=schema,
        quality=Quality(
            valid=bool(valid),
            n_samples=None if n is None else int(n),
            condition_number=_float(cond),
            residual_rms_nm=dict(extra.get("residual_rms_nm", {})),
            warnings=tuple(extra.get("warnings", [])),
            tare_applied=tare.get("applied") is True,
            tare_file=tare.get("file") if isinstance(tare.get("file"), str) else None,
            message=str(extra.get("message", "")),
            findings=tuple(findings_of(extra)),
        ),
        parameters=parameters,
        id=int(sid),
        added_ns=int(added),
        repeatability=json.loads(repeat),
        arm=arm,
        retest=bool(retest),
        cell=cell or "",
        content_sha256=content,
        passive_curves=json.loads(curves),
        passive_model=passive_model,
    )
