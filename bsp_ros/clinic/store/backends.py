"""Database connections for the store: SQLite (default, WAL + synchronous FULL) and PostgreSQL (psycopg 3)."""

from __future__ import annotations

import os
import sqlite3
import tempfile
from abc import ABC, abstractmethod
from collections.abc import Iterator, Sequence
from contextlib import closing, contextmanager
from pathlib import Path
from typing import Any

from bsp_ros.clinic.store.location import is_database_url, redact
from bsp_ros.errors import StoreError

Row = tuple[Any, ...]


class Backend(ABC):
    """One open connection; SQL uses ``?`` placeholders whatever the dialect."""

    dialect: str
    location: str

    @abstractmethod
    def query(self, sql: str, params: Sequence[Any] = ()) -> list[Row]:
        """Run one statement and return its rows (empty for statements without a result)."""

    @abstractmethod
    def transaction(self) -> Any:
        """A context manager: commit on normal exit (durably, before it returns), roll back on error."""

    @abstractmethod
    def tables(self) -> set[str]:
        """Names of the tables in the database (in the default schema)."""

    @abstractmethod
    def is_integrity_error(self, error: BaseException) -> bool:
        """Whether ``error`` is a constraint violation (a duplicate session)."""

    @abstractmethod
    def purge_freed_space(self) -> None:
        """After a delete: rewrite storage so deleted rows leave no bytes behind where the engine allows."""

    @abstractmethod
    def close(self) -> None:
        """Close the connection."""


SQLITE_HEADER = b"SQLite format 3\x00"
"""The first 16 bytes of every SQLite 3 database file."""


def _check_sqlite_header(file: Path) -> None:
    """Refuse an existing file that is not a SQLite database, before SQLite could take it for an empty one
    (it does so for files shorter than a page) and write a store over it."""
    try:
        with open(file, "rb") as stream:
            head = stream.read(len(SQLITE_HEADER))
    except FileNotFoundError:
        return
    except OSError as error:
        raise StoreError(f"cannot read store {file}: {error.strerror}") from None
    if head != SQLITE_HEADER:
        what = "an empty file" if not head else f"a {file.stat().st_size}-byte file without the SQLite header"
        raise StoreError(f"cannot open store {file}: it is {what}, not a bsp_ros session store; not touching it")


def _create_sqlite_file(file: Path) -> None:
    """Create an empty SQLite database at ``file`` atomically: built aside, then linked in place.

    SQLite itself creates an empty file first and writes its header later; another process opening the
    store in between (a therapist's ``bsp sessions list`` while the session recorder starts) would find an
    empty file, which is refused as "not a store". Linking a finished file never shows that state, and
    ``os.link`` fails instead of replacing a file another process created meanwhile.
    """
    handle, name = tempfile.mkstemp(prefix=f".{file.name}.", suffix=".new", dir=file.parent)
    os.close(handle)  # mkstemp's file is private (0600) and empty, which SQLite takes as a new database
    aside = Path(name)
    try:
        with closing(sqlite3.connect(aside)) as conn:
            # Switching a new database to WAL writes its first page (header included).
            conn.execute("PRAGMA journal_mode = WAL").fetchone()
        # Health data: owner only (mkstemp's 0600 is kept); -wal and -shm inherit this.
        try:
            os.link(aside, file)
        except FileExistsError:
            pass  # created by another process meanwhile: use theirs
    finally:
        for leftover in (aside, Path(f"{aside}-wal"), Path(f"{aside}-shm")):
            leftover.unlink(missing_ok=True)


class SqliteBackend(Backend):
    """A SQLite file in WAL mode with ``synchronous=FULL`` and ``secure_delete=ON``."""

    dialect = "sqlite"

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.location = str(path)
        file = Path(path).expanduser()
        if file.is_dir():
            raise StoreError(f"store {file} is a directory, expected a SQLite file")
        _check_sqlite_header(file)
        try:
            file.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
            if not file.exists():
                _create_sqlite_file(file)
            # Autocommit mode: transactions are explicit BEGIN IMMEDIATE ... COMMIT.
            self._conn = sqlite3.connect(file, timeout=10.0, isolation_level=None)
            self._conn.execute("PRAGMA busy_timeout = 10000")
            names = {row[0] for row in self._conn.execute("SELECT name FROM sqlite_master WHERE type = 'table'")}
            if names and "bsp_meta" not in names:
                self._conn.close()
                raise StoreError(f"{file} is a SQLite database but not a bsp_ros session store; not touching it")
            mode = self._conn.execute("PRAGMA journal_mode = WAL").fetchone()[0]
            if str(mode).lower() != "wal":
                raise StoreError(f"store {file} cannot use WAL journal mode (got {mode})")
            self._conn.execute("PRAGMA synchronous = FULL")
            self._conn.execute("PRAGMA secure_delete = ON")
            self._conn.execute("PRAGMA foreign_keys = ON")
        except sqlite3.DatabaseError as error:
            raise StoreError(f"cannot open store {file}: {error}") from None
        except OSError as error:
            raise StoreError(f"cannot create store {file}: {error}") from None

    def query(self, sql: str, params: Sequence[Any] = ()) -> list[Row]:
        try:
            return [tuple(row) for row in self._conn.execute(sql, tuple(params)).fetchall()]
        except sqlite3.IntegrityError:
            raise
        except sqlite3.Error as error:
            raise StoreError(f"store {self.location}: {error}") from None

    @contextmanager
    def transaction(self) -> Iterator[None]:
        self.query("BEGIN IMMEDIATE")
        try:
            yield
        except BaseException:
            if self._conn.in_transaction:
                self._conn.execute("ROLLBACK")
            raise
        self.query("COMMIT")

    def tables(self) -> set[str]:
        return {row[0] for row in self.query("SELECT name FROM sqlite_master WHERE type = 'table'")}

    def is_integrity_error(self, error: BaseException) -> bool:
        return isinstance(error, sqlite3.IntegrityError)

    def purge_freed_space(self) -> None:
        # secure_delete zeroed the freed cells; VACUUM rebuilds the file without the freed pages, and the
        # TRUNCATE checkpoint copies it back from the WAL and empties the -wal file, so neither keeps old bytes.
        self.query("VACUUM")
        busy, _, _ = self.query("PRAGMA wal_checkpoint(TRUNCATE)")[0]
        if busy:
            raise StoreError(
                f"store {self.location}: the rows are deleted, but another process holds the store open, so "
                "its -wal file could not be emptied yet; close the other bsp processes and run `bsp sessions "
                "compact`"
            )

    def close(self) -> None:
        self._conn.close()


class PostgresBackend(Backend):
    """A PostgreSQL database reached by a ``postgresql://`` URL (psycopg 3)."""

    dialect = "postgresql"

    def __init__(self, url: str) -> None:
        self.location = redact(url)
        try:
            import psycopg
        except ImportError:
            raise StoreError(
                "a PostgreSQL store needs psycopg 3: pip install 'psycopg[binary]' (or bsp_ros[postgres])"
            ) from None
        self._psycopg = psycopg
        try:
            self._conn = psycopg.connect(url, autocommit=True, connect_timeout=10)
        except psycopg.Error as error:
            raise StoreError(f"cannot connect to store {self.location}: {error}") from None

    def query(self, sql: str, params: Sequence[Any] = ()) -> list[Row]:
        try:
            cursor = self._conn.execute(sql.replace("?", "%s"), tuple(params))
            return [tuple(row) for row in cursor.fetchall()] if cursor.description else []
        except self._psycopg.IntegrityError:
            raise
        except self._psycopg.Error as error:
            raise StoreError(f"store {self.location}: {error}") from None

    @contextmanager
    def transaction(self) -> Iterator[None]:
        with self._conn.transaction():
            yield

    def tables(self) -> set[str]:
        rows = self.query("SELECT tablename FROM pg_tables WHERE schemaname = current_schema()")
        return {row[0] for row in rows}

    def is_integrity_error(self, error: BaseException) -> bool:
        return isinstance(error, self._psycopg.IntegrityError)

    def purge_freed_space(self) -> None:
        # Rewrites the tables without dead rows. PostgreSQL's WAL segments and backups are the operator's.
        self.query("VACUUM FULL parameters")
        self.query("VACUUM FULL sessions")

    def close(self) -> None:
        self._conn.close()


def connect(location: str | os.PathLike[str]) -> Backend:
    """Open the store at ``location``: a ``postgresql://`` URL, else a SQLite file path."""
    text = os.fspath(location)
    if is_database_url(text):
        return PostgresBackend(text)
    return SqliteBackend(text)
