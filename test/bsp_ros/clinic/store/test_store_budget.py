"""The store keeps each quantity's uncertainty budget through its round trip: from a typed Estimate and from its
JSON, on both backends; a store of the version before the budget migrates with its sessions and no budget."""

from __future__ import annotations

import copy
import math
from typing import Any

import pytest

from bsp_ros.clinic.histories import Patient, session_estimate
from bsp_ros.clinic.store import open_store
from bsp_ros.clinic.store.backends import connect
from bsp_ros.clinic.store.schema import APPLICATION, migration_statements
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.errors import StoreError

UPPER_ARM = ("segments", "upper_arm", "static_moment_kgm")


@pytest.fixture(scope="module")
def document() -> dict[str, Any]:
    """An untared simulated session's estimate (0.2 N of sensor offset per axis), with its budgets."""
    return session_estimate(Patient(), 0, 7)


def _as_another_recording(document: dict[str, Any], digit: str) -> dict[str, Any]:
    """A deep copy of ``document`` that the store takes for another recording (its own content hash)."""
    copied = copy.deepcopy(document)
    copied["session"]["content_sha256"] = digit * 64
    return copied


def _budgets(estimate: Estimate) -> dict[tuple[str, str, str], dict[str, float | None]]:
    return {(g, p, k): dict(q.budget) for g, p, k, q in estimate.quantities() if q.budget is not None}


def test_the_budget_survives_the_store_from_the_estimate_and_its_json(
    document: dict[str, Any], store_location: str
) -> None:
    estimate = Estimate.from_json(document)
    budgets = _budgets(estimate)
    assert UPPER_ARM in budgets and ("joints", "elbow", "coulomb_nm") in budgets
    written = _as_another_recording(document, "1")
    with open_store(store_location) as store:
        store.add_estimate(estimate, "P101")
        store.add_estimate(written, "P102")
    with open_store(store_location) as store:
        (from_typed,) = store.sessions("P101")
        (from_json,) = store.sessions("P102")
    for record in (from_typed, from_json):
        kept = {key: dict(q.budget) for key, q in record.parameters.items() if q.budget is not None}
        assert kept == budgets  # the same quantities have one (what the identification did not decide has none)
        assert len(kept) < len(record.parameters)
        # The estimate's own sum: each kept budget's squares add up to its std squared.
        for key, budget in kept.items():
            std = record.parameters[key].std
            assert std is not None
            assert math.sqrt(sum((u or 0.0) ** 2 for u in budget.values())) == pytest.approx(std, rel=1e-6), key


def test_a_malformed_budget_is_refused(document: dict[str, Any], tmp_path: Any) -> None:
    bad = copy.deepcopy(document)
    bad["segments"]["upper_arm"]["static_moment_kgm"]["budget"] = [0.01, 0.02]
    with open_store(tmp_path / "s.sqlite") as store, pytest.raises(StoreError, match="budget must be an object"):
        store.add_estimate(bad, "P103")
    bad["segments"]["upper_arm"]["static_moment_kgm"]["budget"] = {"sensor_zero": -0.01}
    with open_store(tmp_path / "s.sqlite") as store, pytest.raises(StoreError, match="must not be negative"):
        store.add_estimate(bad, "P103")


def test_a_store_of_the_version_before_the_budget_migrates_without_one(
    document: dict[str, Any], store_location: str
) -> None:
    backend = connect(store_location)
    try:
        with backend.transaction():
            for sql in migration_statements(backend.dialect, 0, 4):
                backend.query(sql)
            backend.query("INSERT INTO bsp_meta (key, value) VALUES ('application', ?)", (APPLICATION,))
            backend.query("INSERT INTO bsp_meta (key, value) VALUES ('schema_version', '4')")
    finally:
        backend.close()
    old = _as_another_recording(document, "2")
    for group in ("segments", "joints"):
        for quantities in old[group].values():
            for q in quantities.values():
                if isinstance(q, dict):
                    q.pop("budget", None)
    with open_store(store_location) as store:
        store.add_estimate(old, "P104")
        store.add_estimate(_as_another_recording(document, "3"), "P105")
        (before,) = store.sessions("P104")
        (after,) = store.sessions("P105")
    assert all(q.budget is None for q in before.parameters.values())
    assert after.parameters[UPPER_ARM].budget is not None


def test_sessions_show_json_carries_the_budget_a_later_add_keeps(
    document: dict[str, Any], tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    import json

    from bsp_ros.cli import main

    store = str(tmp_path / "clinic.sqlite")
    (tmp_path / "estimate.json").write_text(json.dumps(_as_another_recording(document, "3")))
    assert main(["sessions", "add", str(tmp_path / "estimate.json"), "--store", store, "--subject", "P104"]) == 0
    capsys.readouterr()
    assert main(["sessions", "show", "P104", "--json", "--store", store]) == 0
    (shown,) = json.loads(capsys.readouterr().out)
    budget = shown["segments"]["upper_arm"]["static_moment_kgm"]["budget"]
    assert budget == pytest.approx(dict(Estimate.from_json(document).segments["upper_arm"]["static_moment_kgm"].budget))
