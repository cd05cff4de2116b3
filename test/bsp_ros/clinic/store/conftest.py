"""Fixtures for the store tests: a throwaway PostgreSQL server and a store location per backend."""

from __future__ import annotations

import glob
import os
import pwd
import shutil
import socket
import subprocess
import tempfile
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest


def _postgres_bindir() -> Path | None:
    for bindir in sorted(glob.glob("/usr/lib/postgresql/*/bin"), reverse=True):
        if os.access(f"{bindir}/initdb", os.X_OK) and os.access(f"{bindir}/pg_ctl", os.X_OK):
            return Path(bindir)
    found = shutil.which("initdb"), shutil.which("pg_ctl")
    return Path(found[0]).parent if all(found) else None  # type: ignore[arg-type]


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.fixture(scope="session")
def postgres_server() -> Iterator[dict[str, str]]:
    """A PostgreSQL cluster in a temp dir, reachable by unix socket only; skips if it cannot run."""
    pytest.importorskip("psycopg", reason="PostgreSQL tests need psycopg 3 (pip install 'psycopg[binary]')")
    bindir = _postgres_bindir()
    if bindir is None:
        pytest.skip("PostgreSQL tests need initdb and pg_ctl (Debian package postgresql; see .ci/services.sh)")
    prefix: list[str] = []
    base = Path(tempfile.mkdtemp(prefix="bsppg"))  # short: unix socket paths are limited to ~107 bytes
    if os.geteuid() == 0:  # initdb refuses root: run the server as the postgres system user
        try:
            owner = pwd.getpwnam("postgres")
        except KeyError:
            shutil.rmtree(base)
            pytest.skip("running as root and there is no 'postgres' user to run the test server as")
        os.chown(base, owner.pw_uid, owner.pw_gid)
        prefix = ["runuser", "-u", "postgres", "--"]
    data, port = base / "data", str(_free_port())

    def run(*command: str) -> None:
        result = subprocess.run([*prefix, *command], capture_output=True, text=True, timeout=120)
        if result.returncode != 0:
            raise RuntimeError(f"{' '.join(command)} failed:\n{result.stdout}\n{result.stderr}")

    run(str(bindir / "initdb"), "-D", str(data), "-U", "bsp", "-A", "trust", "-E", "UTF8", "--no-locale", "-N")
    options = f"-k {base} -p {port} -c listen_addresses='' -c fsync=off -c full_page_writes=off"
    run(str(bindir / "pg_ctl"), "-D", str(data), "-l", str(base / "log"), "-w", "-t", "60", "-o", options, "start")
    try:
        yield {"host": str(base), "port": port, "user": "bsp"}
    finally:
        subprocess.run([*prefix, str(bindir / "pg_ctl"), "-D", str(data), "-m", "immediate", "stop"], check=False)
        shutil.rmtree(base, ignore_errors=True)


def _url(server: dict[str, str], database: str) -> str:
    return f"postgresql://{server['user']}@/{database}?host={server['host']}&port={server['port']}"


@pytest.fixture
def postgres_url(postgres_server: dict[str, str]) -> Iterator[str]:
    """A fresh, empty database on the test server, dropped afterwards."""
    import psycopg

    name = f"t_{uuid.uuid4().hex[:12]}"
    with psycopg.connect(_url(postgres_server, "postgres"), autocommit=True) as admin:
        admin.execute(f"CREATE DATABASE {name}")
    yield _url(postgres_server, name)
    with psycopg.connect(_url(postgres_server, "postgres"), autocommit=True) as admin:
        admin.execute(f"DROP DATABASE IF EXISTS {name} WITH (FORCE)")


@pytest.fixture(params=["sqlite", "postgresql"])
def store_location(request: pytest.FixtureRequest, tmp_path: Path) -> str:
    """A location for a new store, once per backend."""
    if request.param == "sqlite":
        return str(tmp_path / "store" / "sessions.sqlite")
    return str(request.getfixturevalue("postgres_url"))
