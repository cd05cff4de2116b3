"""Fixtures for the report tests: a store with a subject whose elbow friction changes between sessions."""

from __future__ import annotations

from pathlib import Path

import pytest

from bsp_ros.clinic.store import open_store
from bsp_ros.clinic.store.samples import SAMPLE_START_NS, sample_estimate

WEEK_NS = 7 * 86_400 * 10**9
SUBJECT = "P007"
OTHER = "Q9other"
BODY = {"body_mass_kg": 75.0, "sex": "male", "height_m": 1.78}


@pytest.fixture
def report_store(tmp_path: Path) -> str:
    """A SQLite store: P007 with 6 weekly sessions (2 without tare, 3 not valid, elbow friction jumps at 5)."""
    path = str(tmp_path / "sessions.sqlite")
    with open_store(path) as store:
        for i in range(6):
            planted = {("joints", "elbow", "coulomb_nm"): (0.9, 0.03)} if i >= 4 else {}
            estimate = sample_estimate(
                i,
                start_time_ns=SAMPLE_START_NS + i * WEEK_NS,
                source=f"rec_{i:03d}.mcap",
                subject=BODY,
                overrides=planted,
                valid=i != 2,
                warnings=["too little wrist motion"] if i == 2 else [],
                sem_rel=0.05,
            )
            if i != 1:  # session 2 was recorded without a tare
                estimate["quality"]["tare"] = {"applied": True, "file": f"tare_{i:03d}.yaml"}
            store.add_estimate(estimate, SUBJECT)
        store.add_estimate(sample_estimate(7, source="other_subject.mcap"), OTHER)
    return path
