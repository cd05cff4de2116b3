"""Schema versions: old stores are migrated with their data, newer or foreign ones are refused untouched."""

from __future__ import annotations

import hashlib
import sqlite3
import threading
from pathlib import Path

import pytest

from bsp_ros.cli.session_actions import record_to_json
from bsp_ros.clinic.store import SCHEMA_VERSION, open_store
from bsp_ros.clinic.store.backends import connect
from bsp_ros.clinic.store.samples import SAMPLE_START_NS, sample_estimate
from bsp_ros.clinic.store.schema import APPLICATION, migration_statements
from bsp_ros.errors import StoreError


def _make_version_1_store(location: str) -> None:
    backend = connect(location)
    try:
        with backend.transaction():
            for sql in migration_statements(backend.dialect, 0, 1):
                backend.query(sql)
            backend.query("INSERT INTO bsp_meta (key, value) VALUES ('application', ?)", (APPLICATION,))
            backend.query("INSERT INTO bsp_meta (key, value) VALUES ('schema_version', '1')")
            sid = backend.query(
                "INSERT INTO sessions (subject, session_time_ns, source, method, config_json, estimate_schema, "
                "valid, n_samples, condition_number, quality_json, added_ns) "
                "VALUES ('OLD1', ?, 'v1.mcap', 'static-ols', '{}', 'bsp_ros/core/estimate/1', 1, 500, 12.0, "
                '\'{"residual_rms_nm": {}, "warnings": ["old"]}\', 1) RETURNING id',
                (SAMPLE_START_NS,),
            )[0][0]
            backend.query(
                "INSERT INTO parameters VALUES (?, 'joints', 'elbow', 'coulomb_nm', 0.31, 0.02, 'data')", (sid,)
            )
    finally:
        backend.close()


def _set_version(location: str, version: str) -> None:
    backend = connect(location)
    try:
        backend.query("UPDATE bsp_meta SET value = ? WHERE key = 'schema_version'", (version,))
    finally:
        backend.close()


def test_old_schema_is_migrated_with_its_data(store_location: str) -> None:
    _make_version_1_store(store_location)
    with open_store(store_location) as store:
        assert store.schema_version == SCHEMA_VERSION == 6
        (old,) = store.sessions("OLD1")
        assert old.parameters[("joints", "elbow", "coulomb_nm")].value == 0.31
        assert old.parameters[("joints", "elbow", "coulomb_nm")].budget is None  # none kept then
        assert old.quality.warnings == ("old",) and old.subject_info == {}
        assert old.repeatability == {} and old.quality.tare_applied is False  # not recorded then
        store.add_estimate(sample_estimate(1, subject={"body_mass_kg": 80.0, "sex": "male"}), "OLD1")
    with open_store(store_location) as store:  # migrating is done once
        assert [r.subject_info for r in store.sessions("OLD1")] == [{}, {"body_mass_kg": 80.0, "sex": "male"}]


def test_repeatability_and_tare_round_trip(store_location: str) -> None:
    estimate = sample_estimate(1)
    estimate["quality"]["tare"] = {"applied": True, "file": "/cell/tares/tare_0301.yaml"}
    estimate["repeatability"] = {
        "method": "SEM from the within-session cycle-to-cycle spread",
        "n_cycles": 5,
        "n_valid_cycles": 4,
        "parameters": {
            "joints.elbow.coulomb_nm": {"sem": 0.01, "mdc95": 0.0277, "n": 4},
            "segments.forearm.static_moment_kgm": {"sem": float("nan"), "mdc95": None, "n": 4},
        },
    }
    with open_store(store_location) as store:
        store.add_estimate(estimate, "S01")
    with open_store(store_location) as store:
        (back,) = store.sessions("S01")
    assert back.quality.tare_applied is True and back.quality.tare_file == "tare_0301.yaml"
    shown = record_to_json(back)  # `bsp sessions show --json` round-trips through the store
    with open_store(store_location) as store:
        again = store.add_estimate(shown, "S02")
    assert again.quality.tare_applied and again.repeatability == back.repeatability
    assert back.repeatability["n_valid_cycles"] == 4
    # The MDC is recomputed from the SEM (1.96 sqrt 2 SEM), and an entry without a finite SEM is dropped.
    assert back.repeatability["parameters"] == {
        "joints.elbow.coulomb_nm": {"sem": 0.01, "mdc95": pytest.approx(0.0277186), "n": 4}
    }


def test_newer_schema_is_refused_untouched(store_location: str) -> None:
    with open_store(store_location) as store:
        store.add_estimate(sample_estimate(1), "S01")
    _set_version(store_location, "99")
    with pytest.raises(StoreError, match="schema version 99, newer than this bsp_ros understands"):
        open_store(store_location)
    _set_version(store_location, str(SCHEMA_VERSION))
    with open_store(store_location) as store:
        assert len(store.sessions("S01")) == 1


def test_foreign_database_is_refused_untouched(store_location: str) -> None:
    backend = connect(store_location) if "://" in store_location else None
    if backend is None:
        Path(store_location).parent.mkdir(parents=True)
        with sqlite3.connect(store_location) as raw:
            raw.execute("CREATE TABLE topics (id INTEGER PRIMARY KEY, name TEXT)")
            raw.execute("INSERT INTO topics (name) VALUES ('/ft_sensor/wrench')")
        raw.close()
        before = hashlib.sha256(Path(store_location).read_bytes()).hexdigest()
    else:
        backend.query("CREATE TABLE topics (id INTEGER PRIMARY KEY, name TEXT)")
        backend.close()
    with pytest.raises(StoreError, match="not a bsp_ros session store"):
        open_store(store_location)
    if backend is None:
        assert hashlib.sha256(Path(store_location).read_bytes()).hexdigest() == before
        assert not Path(store_location + "-wal").exists()


def test_file_that_is_not_a_database_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "notes.sqlite"
    path.write_text("this is not a database, it is a text file with some length " * 20)
    with pytest.raises(StoreError, match="cannot open store"):
        open_store(path)
    assert path.read_text().startswith("this is not a database")


def test_stores_opened_at_once_by_several_processes_never_see_an_empty_file(tmp_path: Path) -> None:
    # A session recorder creating the store while a therapist lists sessions: SQLite alone shows the
    # second an empty file, which the store refuses as not a store.
    paths = [tmp_path / f"s{k}.sqlite" for k in range(20)]
    errors: list[BaseException] = []

    def open_all() -> None:
        for path in paths:
            try:
                with open_store(path) as store:
                    store.sessions()
            except BaseException as error:
                errors.append(error)

    threads = [threading.Thread(target=open_all) for _ in range(6)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.endswith(("-wal", "-shm"))) == sorted(
        p.name for p in paths
    )


def test_sqlite_store_is_wal_full_and_private(tmp_path: Path) -> None:
    path = tmp_path / "deep" / "dir" / "s.sqlite"
    with open_store(path) as store:
        store.add_estimate(sample_estimate(1), "S01")
    assert path.stat().st_mode & 0o077 == 0
    with sqlite3.connect(path) as raw:
        assert raw.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    raw.close()


def test_default_location(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from bsp_ros.clinic.store import default_location

    monkeypatch.delenv("BSP_STORE", raising=False)
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "xdg"))
    assert default_location() == str(tmp_path / "xdg" / "bsp_ros" / "sessions.sqlite")
    monkeypatch.delenv("XDG_DATA_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert default_location() == str(tmp_path / "home" / ".local" / "share" / "bsp_ros" / "sessions.sqlite")
    monkeypatch.setenv("BSP_STORE", "postgresql://bsp@db/bsp")
    assert default_location() == "postgresql://bsp@db/bsp"
