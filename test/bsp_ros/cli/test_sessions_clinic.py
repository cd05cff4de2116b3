"""`bsp subjects` and `bsp sessions` for the clinic: a bag identified with tare and passive model, removing,
refusing duplicates and future dates, confirming erasure, and stores that must exist for reading."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest
from cli_run import bsp

from bsp_ros.cli import main
from bsp_ros.clinic.store import open_store
from bsp_ros.clinic.store.samples import SAMPLE_START_NS, sample_estimate

NUISANCE = ("--force-offset", "3", "-3", "3", "--handle-mass", "0.3", "--handle-com", "0", "0.02", "0.05")
DAY_NS = 86_400 * 10**9


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("clinic_bags")
    out = {"tare": root / "tare_swing", "session": root / "session"}
    swing = ("--tare", "--duration", "20", "--tare-swing", "20", "20", "0", "--seed", "4")
    assert main(["simulate", "--out", str(out["tare"]), *swing, *NUISANCE]) == 0
    session = ("--duration", "120", "--seed", "4", "--viscous", "0", "0.5", "0")
    assert main(["simulate", "--out", str(out["session"]), *session, *NUISANCE]) == 0
    assert main(["tare", str(out["tare"]), "--out", str(root / "t.yaml")]) == 0
    out["tare_file"] = root / "t.yaml"
    return out


def test_a_bag_is_stored_with_its_options_tare_body_data_and_repeatability(
    bags: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    store = str(tmp_path / "s.sqlite")
    code, out, _ = bsp(
        capsys,
        "subjects",
        "set",
        "S1",
        "--body-mass",
        "68",
        "--height",
        "1.65",
        "--sex",
        "female",
        "--arm",
        "left",
        "--affected",
        "left",
        "--store",
        store,
    )
    assert code == 0 and "body mass 68 kg" in out and "affected arm left" in out
    code, out, err = bsp(
        capsys,
        "sessions",
        "add",
        str(bags["session"]),
        "--subject",
        "S1",
        "--tare",
        str(bags["tare_file"]),
        "--passive",
        "coulomb+viscous",
        "--time",
        "2024-06-01T09:00Z",
        "--store",
        store,
    )
    assert code == 0, err
    assert "added session 1 of S1, left arm at 2024-06-01T09:00:00Z" in out and "(valid," in out
    with open_store(store) as opened:
        (record,) = opened.sessions("S1")
    assert record.quality.tare_applied and record.quality.tare_file == "t.yaml"
    config = record.config
    assert config["passive"] == "coulomb+viscous" and config["tare_file"] == "t.yaml"
    assert (config["sex"], config["body_mass_kg"], config["height_m"]) == ("female", 68.0, 1.65)  # the record's
    assert record.subject_info == {"body_mass_kg": 68.0, "height_m": 1.65, "sex": "female"}
    assert ("joints", "elbow", "viscous_nms") in record.parameters
    viscous = record.parameters[("joints", "elbow", "viscous_nms")]
    assert abs(viscous.value - 0.5) < 4 * viscous.std + 0.05  # the simulated 0.5 N m s/rad
    repeat = record.repeatability
    assert repeat["n_valid_cycles"] >= 3 and "Within-session spread" in repeat["method"]
    assert repeat["parameters"]["joints.elbow.coulomb_nm"]["sem"] > 0
    digest = hashlib.sha256(b"".join(f.read_bytes() for f in sorted(bags["session"].glob("*.mcap")))).hexdigest()
    assert record.content_sha256 == digest
    # The same recording again, under another time: refused before it is identified, nothing added.
    import bsp_ros.cli.session_actions as sessions_cli

    def identified(*_: object) -> None:
        raise AssertionError("a stored recording was identified again before being refused")

    monkeypatch.setattr(sessions_cli, "identify_bag_for_store", identified)
    code, _, err = bsp(
        capsys, "sessions", "add", str(bags["session"]), "--subject", "S1", "--time", "2024-06-08", "--store", store
    )
    assert code == 5 and "duplicate recording" in err and "session 1 of S1" in err
    with open_store(store) as opened:
        assert len(opened.sessions("S1")) == 1


def _add_json(tmp_path: Path, capsys: pytest.CaptureFixture[str], store: str, seed: int, day: int) -> None:
    path = tmp_path / f"e{seed}.json"
    path.write_text(json.dumps(sample_estimate(seed, start_time_ns=SAMPLE_START_NS + day * DAY_NS)))
    assert bsp(capsys, "sessions", "add", str(path), "--subject", "S1", "--store", store)[0] == 0


def test_remove_asks_then_renumbers(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store = str(tmp_path / "s.sqlite")
    for seed, day in ((1, 0), (2, 7), (3, 14)):
        _add_json(tmp_path, capsys, store, seed, day)
    code, _, err = bsp(capsys, "sessions", "remove", "S1", "2", "--store", store)
    assert code == 2 and "--yes" in err  # not a terminal: not asked, refused
    code, out, _ = bsp(capsys, "sessions", "remove", "S1", "2", "--yes", "--store", store)
    assert code == 0 and "removed session 2 of S1 (2024-06-08" in out
    with open_store(store) as opened:
        assert [(r.number, r.session_time_ns) for r in opened.sessions("S1")] == [
            (1, SAMPLE_START_NS),
            (2, SAMPLE_START_NS + 14 * DAY_NS),
        ]
    code, _, err = bsp(capsys, "sessions", "remove", "S1", "3", "--yes", "--store", store)
    assert code == 5 and "sessions 1 to 2, not 3" in err


def test_future_dates_are_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store = str(tmp_path / "s.sqlite")
    path = tmp_path / "e.json"
    path.write_text(json.dumps(sample_estimate(1)))
    code, _, err = bsp(
        capsys, "sessions", "add", str(path), "--subject", "S1", "--time", "2031-03-01", "--store", store
    )
    assert code == 2 and "--time 2031-03-01 00:00 UTC is in the future" in err
    path.write_text(json.dumps(sample_estimate(1, start_time_ns=1_930_000_000 * 10**9)))  # 2031
    code, _, err = bsp(capsys, "sessions", "add", str(path), "--subject", "S1", "--store", store)
    assert code == 2 and "in the future" in err


def test_erase_asks_and_reading_needs_an_existing_store(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store = str(tmp_path / "s.sqlite")
    _add_json(tmp_path, capsys, store, 1, 0)
    code, _, err = bsp(capsys, "sessions", "erase", "S1", "--store", store)
    assert code == 2 and "--yes" in err
    code, out, _ = bsp(capsys, "sessions", "--store", store, "list")  # --store before the action
    assert code == 0 and "S1" in out
    assert bsp(capsys, "sessions", "--store", store, "erase", "S1", "--yes")[0] == 0
    typo = tmp_path / "sesions.sqlite"
    for argv in (
        ("sessions", "list", "--store", str(typo)),
        ("sessions", "show", "S1", "--store", str(typo)),
        ("sessions", "export", "--csv", str(tmp_path / "x.csv"), "--store", str(typo)),
        ("report", "S1", "--out", str(tmp_path / "r.html"), "--store", str(typo)),
        ("subjects", "show", "S1", "--store", str(typo)),
    ):
        code, _, err = bsp(capsys, *argv)
        assert code == 5 and f"no store at {typo}" in err, argv
    assert not typo.exists()


def test_report_says_changes_cannot_be_judged_without_retests(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    store = str(tmp_path / "s.sqlite")
    for seed, day in ((1, 0), (2, 7)):
        _add_json(tmp_path, capsys, store, seed, day)
    code, out, _ = bsp(capsys, "report", "S1", "--store", store, "--csv", str(tmp_path / "r.csv"))
    assert code == 0 and "cannot be judged against measurement error" in out and "--retest" in out
    code, _, err = bsp(capsys, "subjects", "set", "Maria_Garcia", "--sex", "female", "--store", store)
    assert code == 2 and "identifies a person" in err
