"""SIGKILL the writer at random points: the store always opens, is intact and keeps every acknowledged session."""

from __future__ import annotations

import random
import sqlite3
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from bsp_ros.clinic.store import open_store

WRITER = Path(__file__).with_name("kill_writer.py")
KILLS = 100
# Independent stores killed in parallel, to keep the runtime down: after each kill the whole store is read back (in
# this process, the lanes' checks taking turns), so four stores of 25 kills take a third of the time two of 50 do.
LANES = 4
SEED = 20240601


def _kill_once(path: Path, first_index: int, rng: random.Random) -> set[tuple[str, int]]:
    writer = subprocess.Popen(
        [sys.executable, str(WRITER), str(path), str(first_index)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    assert writer.stdout is not None
    if rng.random() < 0.2:  # anywhere, including while the store is created or migrated
        time.sleep(rng.uniform(0.0, 0.25))
    else:  # while sessions are being committed
        writer.stdout.readline()
        time.sleep(rng.uniform(0.0, 0.12))
    writer.kill()
    out, err = writer.communicate(timeout=10)
    assert writer.returncode == -9, f"writer ended by itself ({writer.returncode}): {err}"
    acked = set()
    for line in out.splitlines(keepends=True):
        if line.startswith("ack ") and line.endswith("\n"):
            _, subject, time_ns = line.split()
            acked.add((subject, int(time_ns)))
    return acked


def _check(path: Path, acked: set[tuple[str, int]]) -> None:
    if not path.exists():
        assert not acked
        return
    raw = sqlite3.connect(path)
    try:
        assert raw.execute("PRAGMA integrity_check").fetchall() == [("ok",)]
    finally:
        raw.close()
    with open_store(path) as store:
        stored = {(r.subject, r.session_time_ns): r for r in store.sessions()}
    missing = acked - set(stored)
    assert not missing, f"{len(missing)} acknowledged sessions lost, e.g. {sorted(missing)[:3]}"
    assert all(len(record.parameters) == 18 for record in stored.values())  # no half-written session


def _lane(directory: Path, lane: int) -> int:
    rng = random.Random(SEED + lane)
    path = directory / f"lane{lane}.sqlite"
    acked: set[tuple[str, int]] = set()
    for kill in range(KILLS // LANES):
        acked |= _kill_once(path, (lane * KILLS + kill) * 10_000, rng)
        _check(path, acked)
    return len(acked)


@pytest.mark.slow
def test_killed_writer_never_loses_acknowledged_sessions(tmp_path: Path) -> None:
    with ThreadPoolExecutor(LANES) as pool:
        counts = list(pool.map(lambda lane: _lane(tmp_path, lane), range(LANES)))
    assert sum(counts) > KILLS  # the kills did land between and during commits
