"""`bsp identify --json` then `bsp sessions add RESULT.json`: the body data it was made with, and its bag's identity."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_run import bsp

from bsp_ros.bag.fingerprint import content_sha256
from bsp_ros.cli import main
from bsp_ros.clinic.store import open_store

RECORD = ("--body-mass", "68", "--height", "1.65", "--sex", "female")


@pytest.fixture(scope="module")
def recording(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """One simulated session (seeded, elbow friction 0.3 Nm) and its results: default prior and the record's."""
    root = tmp_path_factory.mktemp("json_route")
    bag, default, own = root / "s2", root / "s2.json", root / "s2_record.json"
    simulate = ("--duration", "40", "--seed", "7", "--coulomb", "0.5", "0.3", "0.06")
    assert main(["simulate", "--out", str(bag), *simulate]) == 0
    assert main(["identify", str(bag), "--json", str(default)]) == 0
    assert main(["identify", str(bag), "--json", str(own), *RECORD]) == 0
    return {"bag": bag, "default": default, "own": own}


def _store_with_record(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> str:
    store = str(tmp_path / "s.sqlite")
    assert bsp(capsys, "subjects", "set", "S1", *RECORD, "--store", store)[0] == 0
    return store


def test_a_result_keeps_the_body_data_it_was_made_with_and_says_so(
    recording: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    store = _store_with_record(tmp_path, capsys)
    result = json.loads(recording["default"].read_text())
    assert result["subject"] == {"body_mass_kg": None, "height_m": None, "sex": "male"}  # the population prior
    code, out, err = bsp(
        capsys,
        "sessions",
        "add",
        str(recording["default"]),
        "--subject",
        "S1",
        "--time",
        "2024-06-01",
        "--store",
        store,
    )
    assert code == 0 and "added session 1 of S1" in out
    with open_store(store) as opened:
        (record,) = opened.sessions("S1")
    assert record.subject_info == {"sex": "male"}  # not the record's female 68 kg, 1.65 m
    forearm = record.parameters[("segments", "forearm", "mass_kg")]
    assert forearm.value == result["segments"]["forearm"]["mass_kg"]["value"]  # stored as computed, not re-labelled
    (warning,) = err.splitlines()
    assert warning.startswith("warning: s2.json was identified with body data male, body mass not given")
    assert "not S1's record (female, 68 kg, 1.65 m)" in warning
    assert "`bsp sessions add BAG --subject S1`" in warning
    assert "`bsp identify BAG --body-mass 68 --height 1.65 --sex female --json RESULT.json`" in warning


def test_a_result_made_with_the_records_body_data_is_stored_without_a_warning(
    recording: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    store = _store_with_record(tmp_path, capsys)
    code, _, err = bsp(
        capsys, "sessions", "add", str(recording["own"]), "--subject", "S1", "--time", "2024-06-01", "--store", store
    )
    assert code == 0 and err == ""
    with open_store(store) as opened:
        (record,) = opened.sessions("S1")
    assert record.subject_info == {"body_mass_kg": 68.0, "height_m": 1.65, "sex": "female"}


def test_the_result_of_a_stored_bag_is_refused_as_the_same_recording(
    recording: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    store = _store_with_record(tmp_path, capsys)
    digest = content_sha256(recording["bag"])
    assert json.loads(recording["default"].read_text())["session"]["content_sha256"] == digest
    code, _, err = bsp(
        capsys, "sessions", "add", str(recording["bag"]), "--subject", "S1", "--time", "2024-06-01", "--store", store
    )
    assert code == 0, err
    for result in ("default", "own"):  # whichever body data the result was made with
        code, _, err = bsp(
            capsys,
            "sessions",
            "add",
            str(recording[result]),
            "--subject",
            "S1",
            "--time",
            "2024-06-08",
            "--store",
            store,
        )
        assert code == 5
        assert err == (
            "bsp sessions: error: duplicate recording: the same recording is already stored as session 1 of S1 "
            "(2024-06-01T00:00:00Z); nothing was added\n"
        )
    with open_store(store) as opened:
        (record,) = opened.sessions("S1")
    assert record.content_sha256 == digest
