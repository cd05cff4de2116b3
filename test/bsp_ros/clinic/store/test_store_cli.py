"""`bsp sessions` end to end: add JSON (and bags), list, show, export, erase, and clear errors."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
from cli_run import bsp

from bsp_ros.clinic.store import open_store
from bsp_ros.clinic.store.samples import SAMPLE_START_NS, sample_estimate


def _write(path: Path, estimate: dict[str, Any]) -> Path:
    path.write_text(json.dumps(estimate))
    return path


def test_add_list_show_export_erase(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store = str(tmp_path / "s.sqlite")
    first = _write(tmp_path / "a.json", sample_estimate(1))
    second = _write(tmp_path / "b.json", sample_estimate(2, start_time_ns=SAMPLE_START_NS + 10**12))
    code, out, _ = bsp(capsys, "sessions", "add", str(first), "--subject", "P007", "--store", store)
    assert code == 0 and "added session 1 of P007 at 2024-06-01T07:00:00Z from session.mcap" in out
    assert bsp(capsys, "sessions", "add", str(second), "--subject", "P007", "--store", store)[0] == 0
    code, out, _ = bsp(capsys, "sessions", "list", "--store", store)
    assert code == 0 and "P007" in out and " 2 " in out
    code, out, _ = bsp(capsys, "sessions", "show", "P007", "--store", store)
    assert code == 0 and out.count("session ") == 2 and "forearm.static_moment_kgm" in out
    code, out, _ = bsp(capsys, "sessions", "show", "P007", "--json", "--store", store)
    shown = json.loads(out)
    assert shown[0]["joints"]["elbow"]["coulomb_nm"] == sample_estimate(1)["joints"]["elbow"]["coulomb_nm"]
    csv_path = tmp_path / "out.csv"
    assert bsp(capsys, "sessions", "export", "--csv", str(csv_path), "--store", store)[0] == 0
    assert len(csv_path.read_text().splitlines()) == 1 + 2 * 18
    code, out, _ = bsp(capsys, "sessions", "erase", "P007", "--yes", "--store", store)
    assert code == 0 and "erased 2 session(s) of P007" in out
    code, _, err = bsp(capsys, "sessions", "show", "P007", "--store", store)
    assert code == 5 and "unknown subject P007" in err


def test_store_from_environment(tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: Any) -> None:
    monkeypatch.setenv("BSP_STORE", str(tmp_path / "env.sqlite"))
    assert (
        bsp(capsys, "sessions", "add", str(_write(tmp_path / "a.json", sample_estimate(1))), "--subject", "E1")[0] == 0
    )
    assert (tmp_path / "env.sqlite").exists()


def test_time_and_source_options_fill_a_bare_estimate(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store = str(tmp_path / "s.sqlite")
    bare = _write(tmp_path / "rec-3.json", sample_estimate(1, start_time_ns=None, source=None, method=None))
    code, _, err = bsp(capsys, "sessions", "add", str(bare), "--subject", "S1", "--store", store)
    assert code == 5 and "--time" in err
    code, out, _ = bsp(
        capsys, "sessions", "add", str(bare), "--subject", "S1", "--time", "2024-06-02T08:00:00Z", "--store", store
    )
    assert code == 0 and "at 2024-06-02T08:00:00Z from rec-3.json" in out


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("{not json", "is not valid JSON"),
        ("[1, 2, 3]", "holds a JSON list"),
        (json.dumps({"type": "FeatureCollection", "features": []}), "foreign JSON"),
        (json.dumps({"schema": "bsp_ros/core/estimate/2"}), "unsupported estimate schema"),
    ],
)
def test_bad_input_is_a_clear_error_and_nothing_lost(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: str, message: str
) -> None:
    store = str(tmp_path / "s.sqlite")
    assert (
        bsp(
            capsys,
            "sessions",
            "add",
            str(_write(tmp_path / "ok.json", sample_estimate(1))),
            "--subject",
            "S1",
            "--store",
            store,
        )[0]
        == 0
    )
    bad = tmp_path / "bad.json"
    bad.write_text(content)
    code, out, err = bsp(capsys, "sessions", "add", str(bad), "--subject", "S1", "--store", store)
    assert code == 5 and message in err and out == ""
    with open_store(store) as opened:
        assert len(opened.sessions("S1")) == 1


def test_duplicate_and_bad_subject(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    store = str(tmp_path / "s.sqlite")
    path = str(_write(tmp_path / "a.json", sample_estimate(1)))
    assert bsp(capsys, "sessions", "add", path, "--subject", "S1", "--store", store)[0] == 0
    code, _, err = bsp(capsys, "sessions", "add", path, "--subject", "S1", "--store", store)
    assert code == 5 and "duplicate session" in err
    code, _, err = bsp(capsys, "sessions", "add", path, "--subject", "Jane Doe", "--store", store)
    assert code == 2 and "not a pseudonym" in err
    code, _, err = bsp(capsys, "sessions", "add", str(tmp_path / "missing.json"), "--subject", "S1", "--store", store)
    assert code == 2 and "does not exist" in err
