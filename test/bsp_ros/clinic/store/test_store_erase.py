"""Erasure leaves no bytes of the subject in the SQLite file or its WAL."""

from __future__ import annotations

import struct
from pathlib import Path

from bsp_ros.clinic.store import open_store
from bsp_ros.clinic.store.samples import SAMPLE_START_NS, sample_estimate

DAY_NS = 86_400 * 10**9
GONE = "Zq7xErasedSubject"
KEPT = "Kept0Subject"
GONE_VALUE = 1.2345678901234567  # distinctive doubles: SQLite stores REALs as 8-byte big-endian IEEE
KEPT_VALUE = 7.6543210987654321


def _files(path: Path) -> bytes:
    return b"".join(p.read_bytes() for p in (path, Path(f"{path}-wal")) if p.exists())


def _needles(subject: str, value: float, source: str) -> list[bytes]:
    return [subject.encode(), struct.pack(">d", value), source.encode()]


def test_erase_leaves_no_bytes_in_db_or_wal(tmp_path: Path) -> None:
    path = tmp_path / "sessions.sqlite"
    with open_store(path) as store:
        for day in range(4):
            for subject, value, source in ((GONE, GONE_VALUE, "Zq7x-rec.mcap"), (KEPT, KEPT_VALUE, "kept.mcap")):
                estimate = sample_estimate(
                    day,
                    start_time_ns=SAMPLE_START_NS + day * DAY_NS,
                    source=f"{day}-{source}",
                    config={"note": f"cfg-{source}"},
                    overrides={("joints", "elbow", "viscous_nms"): (value, 0.01)},
                )
                store.add_estimate(estimate, subject)
        before = _files(path)
        gone, kept = _needles(GONE, GONE_VALUE, "Zq7x-rec.mcap"), _needles(KEPT, KEPT_VALUE, "kept.mcap")
        assert all(needle in before for needle in gone + kept)  # the check can see them
        assert store.erase(GONE) == 4
        after = _files(path)
        assert [needle for needle in gone if needle in after] == []
        assert all(needle in after for needle in kept)
        assert not Path(f"{path}-wal").exists() or Path(f"{path}-wal").stat().st_size == 0
        assert [s.subject for s in store.subjects()] == [KEPT]
    # and still after the store is closed and reopened
    assert [needle for needle in gone if needle in _files(path)] == []
    with open_store(path) as store:
        assert len(store.sessions(KEPT)) == 4
