"""A stored and reported session reads the typed estimate's own values: the same quantities, verdict and findings
whether the store is handed the Estimate or its JSON, and the report's points are those numbers."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bsp_ros.bag.offline import estimate_bags
from bsp_ros.clinic.report import analyse
from bsp_ros.clinic.store import open_store
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.pipeline import IdentifyOptions

SAMPLES = Path(__file__).resolve().parents[4] / "bags"
SESSION_NS = 1_709_285_400_000_000_000  # 2024-03-01T09:30Z


@pytest.fixture(scope="module")
def estimate() -> Estimate:
    """The typed estimate of the sample human bag (a recorded session)."""
    return estimate_bags([SAMPLES / "human_arm_60s"], IdentifyOptions())


def test_the_store_keeps_the_typed_estimate_s_quantities_and_verdict(estimate: Estimate, tmp_path: Path) -> None:
    with open_store(tmp_path / "typed.sqlite") as store:
        store.add_estimate(estimate, "P001", session_time_ns=SESSION_NS)
        (typed,) = store.sessions("P001")
    with open_store(tmp_path / "json.sqlite") as store:
        store.add_estimate(json.loads(json.dumps(estimate.to_json())), "P001", session_time_ns=SESSION_NS)
        (written,) = store.sessions("P001")
    assert estimate.valid and typed.quality.valid
    quantities = list(estimate.quantities())
    assert len(quantities) > 20
    for group, owner, key, q in quantities:
        stored = typed.parameters[(group, owner, key)]
        assert (stored.value, stored.std, stored.source) == (q.value, q.std, q.source), (group, owner, key)
        assert written.parameters[(group, owner, key)] == stored
    assert typed.quality.findings == estimate.quality.findings == written.quality.findings
    assert typed.quality.warnings == estimate.quality.warnings and typed.quality.message == estimate.quality.message
    assert typed.quality.n_samples == estimate.quality.n_samples and typed.content_sha256 == written.content_sha256
    assert typed.quality.tare_applied is estimate.quality.tare_applied is False
    given = {k: v for k, v in (estimate.subject or {}).items() if v is not None}
    assert typed.subject_info == written.subject_info == given and given


def test_the_report_shows_the_estimate_s_numbers(estimate: Estimate, tmp_path: Path) -> None:
    with open_store(tmp_path / "clinic.sqlite") as store:
        store.add_estimate(estimate, "P002", session_time_ns=SESSION_NS)
        analysis = analyse("P002", store.sessions("P002"), pool=store.sessions())
    series = {s.key: s for s in analysis.arm_series(None)}
    for key in (("segments", "forearm", "static_moment_kgm"), ("joints", "elbow", "coulomb_nm")):
        q = estimate.quantity(key[2], key[1])
        (point,) = series[key].points
        assert q is not None and point.valid
        assert (point.value, point.std, point.source) == (q.value, q.std, q.source)
