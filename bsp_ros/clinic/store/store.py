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
from bsp_ros.clinic.store.estimate import parse_estimate
from bsp_ros.clinic.store.location import default_location
from bsp_ros.clinic.store.records import ParamKey, Quality, Quantity, SessionRecord, SubjectSummary, format_time
from bsp_ros.clinic.store.schema import APPLICATION, SCHEMA_VERSION, migration_statements
from bsp_ros.clinic.store.subject import check_subject_id
from bsp_ros.errors import StoreError

_MIGRATION_LOCK = 0x6273_7073  # PostgreSQL advisory lock key ("bsps") serialising migrations
_SESSION_COLUMNS = (
    "id, subject, session_time_ns, source, method, config_json, subject_info_json, estimate_schema, "
    "valid, n_samples, condition_number, quality_json, added_ns, repeatability_json"
)


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
        estimate: Mapping[str, Any],
        subject: str,
        *,
        session_time_ns: int | None = None,
        source: str | None = None,
    ) -> SessionRecord:
        """Check a `bsp_ros/core/estimate/1` dict and store it as a session of ``subject``.

        Parameters
        ----------
        estimate : Mapping
            The estimate (see :func:`bsp_ros.clinic.store.estimate.parse_estimate`).
        subject : str
            Pseudonymous subject id.
        session_time_ns : int, optional
            Session start; overrides the estimate's ``session.start_time_ns``.
        source : str, optional
            Recording name; overrides the estimate's ``session.source``.

        Returns
        -------
        SessionRecord
            The stored session, with its ``id``; returned only after the commit.
        """
        record = parse_estimate(estimate, subject, session_time_ns=session_time_ns, source=source)
        return self.add(record)

    def add(self, record: SessionRecord) -> SessionRecord:
        """Store one session; return it with ``id`` and ``added_ns`` set, after the commit.

        Raises
        ------
        StoreError
            If the subject already has a session with the same time and source.
        """
        check_subject_id(record.subject)
        added_ns = time.time_ns()
        quality: dict[str, Any] = {
            "residual_rms_nm": record.quality.residual_rms_nm,
            "warnings": list(record.quality.warnings),
            "tare": {"applied": record.quality.tare_applied, "file": record.quality.tare_file},
        }
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
                rows = self._backend.query(
                    "INSERT INTO sessions (subject, session_time_ns, source, method, config_json, "
                    "subject_info_json, estimate_schema, valid, n_samples, condition_number, quality_json, "
                    "added_ns, repeatability_json) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) RETURNING id",
                    (
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
                    ),
                )
                session_id = int(rows[0][0])
                for (group, part, quantity), q in record.parameters.items():
                    self._backend.query(
                        "INSERT INTO parameters (session_id, grp, part, quantity, value, std, source) "
                        "VALUES (?, ?, ?, ?, ?, ?, ?)",
                        (session_id, group, part, quantity, q.value, q.std, q.source),
                    )
        except Exception as error:
            if self._backend.is_integrity_error(error):
                raise duplicate from None
            raise
        return replace(record, id=session_id, added_ns=added_ns)

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
        parameters: dict[int, dict[ParamKey, Quantity]] = {int(row[0]): {} for row in rows}
        for sid, group, part, quantity, value, std, source in self._backend.query(
            "SELECT session_id, grp, part, quantity, value, std, source FROM parameters "
            f"WHERE session_id IN ({inner}) ORDER BY session_id, grp, part, quantity",
            params,
        ):
            parameters[int(sid)][(group, part, quantity)] = Quantity(_float(value), _float(std), source)
        return [_record(row, parameters[int(row[0])]) for row in rows]

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
            if count == 0:
                raise StoreError(f"unknown subject {subject}: the store {self.location} holds no sessions of it")
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


def open_store(location: str | os.PathLike[str] | None = None) -> Store:
    """Open (creating or migrating if needed) the store at ``location``.

    Parameters
    ----------
    location : str or PathLike, optional
        A SQLite file path or a ``postgresql://`` URL; None means :func:`default_location`.

    Returns
    -------
    Store
        The open store; close it (or use it as a context manager) when done.

    Raises
    ------
    StoreError
        If the location is not a bsp_ros store, cannot be opened, or has a newer schema.
    """
    return Store(connect(default_location() if location is None else location))


def _dumps(value: Any) -> str:
    return json.dumps(value, sort_keys=True, allow_nan=False, separators=(",", ":"))


def _float(value: Any) -> float | None:
    return None if value is None else float(value)


def _record(row: tuple[Any, ...], parameters: dict[ParamKey, Quantity]) -> SessionRecord:
    sid, subject, time_ns, source, method, config, info, schema, valid, n, cond, quality, added, repeat = row
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
        ),
        parameters=parameters,
        id=int(sid),
        added_ns=int(added),
        repeatability=json.loads(repeat),
    )
