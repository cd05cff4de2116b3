"""The store keeps the passive model an identification used beside the one it was configured with (``auto``
chose it on a simulated elbow with a spring), on both backends; a store of the version before migrates, its
sessions with no model used, and the export says so with an empty cell."""

from __future__ import annotations

import copy
import csv
import io
from typing import Any

import pytest

from bsp_ros.clinic.histories import Patient, session_estimate
from bsp_ros.clinic.store import open_store, write_sessions_csv
from bsp_ros.clinic.store.backends import connect
from bsp_ros.clinic.store.schema import APPLICATION, migration_statements
from bsp_ros.core.estimate_schema import Estimate


@pytest.fixture(scope="module")
def document() -> dict[str, Any]:
    """A session of an elbow with a 1.5 Nm/rad spring, identified with ``--passive auto``."""
    return session_estimate(Patient(passive="auto", stiffness_nm_per_rad=(0.0, 1.5, 0.0)), 0, 7)


def _another_recording(document: dict[str, Any], digit: str) -> dict[str, Any]:
    copied = copy.deepcopy(document)
    copied["session"]["content_sha256"] = digit * 64
    return copied


def test_the_model_auto_chose_is_stored_beside_the_configured_one(
    document: dict[str, Any], store_location: str
) -> None:
    chosen = document["diagnostics"]["passive_model"]
    assert document["session"]["config"]["passive"] == "auto" and "stiffness" in chosen  # the spring was found
    with open_store(store_location) as store:
        store.add_estimate(Estimate.from_json(document), "P201")
        store.add_estimate(_another_recording(document, "1"), "P202")
    with open_store(store_location) as store:
        records = store.sessions()
        stream = io.StringIO()
        write_sessions_csv(records, stream)
    assert [(r.config["passive"], r.passive_model) for r in records] == [("auto", chosen)] * 2
    rows = list(csv.DictReader(io.StringIO(stream.getvalue())))
    assert {(r["passive_model_configured"], r["passive_model"]) for r in rows} == {("auto", chosen)}


def test_a_store_of_the_version_before_migrates_with_no_model_used(
    document: dict[str, Any], store_location: str
) -> None:
    backend = connect(store_location)
    try:
        with backend.transaction():
            for sql in migration_statements(backend.dialect, 0, 5):
                backend.query(sql)
            backend.query("INSERT INTO bsp_meta (key, value) VALUES ('application', ?)", (APPLICATION,))
            backend.query("INSERT INTO bsp_meta (key, value) VALUES ('schema_version', '5')")
            backend.query(
                "INSERT INTO sessions (subject, session_time_ns, source, method, config_json, estimate_schema, valid, "
                "quality_json, added_ns) VALUES ('P203', ?, 'old_bag', 'joint', '{\"passive\": \"auto\"}', "
                "'bsp_ros/core/estimate/1', 1, '{}', 0)",
                (document["session"]["start_time_ns"],),
            )
            backend.query(
                "INSERT INTO parameters (session_id, grp, part, quantity, value, std, source) VALUES ((SELECT id "
                "FROM sessions WHERE subject = 'P203'), 'segments', 'forearm', 'static_moment_kgm', 0.5, 0.01, 'data')"
            )
    finally:
        backend.close()
    with open_store(store_location) as store:
        assert store.schema_version == 6
        store.add_estimate(_another_recording(document, "2"), "P204")
        (old,) = store.sessions("P203")
        (new,) = store.sessions("P204")
        stream = io.StringIO()
        write_sessions_csv([old, new], stream)
    assert old.passive_model is None and new.passive_model == document["diagnostics"]["passive_model"]
    rows = list(csv.DictReader(io.StringIO(stream.getvalue())))
    by_source = {r["session_source"]: r["passive_model"] for r in rows}
    assert by_source == {"old_bag": "", document["session"]["source"]: new.passive_model}
