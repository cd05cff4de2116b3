"""docs/api.md's example runs as written (in a fresh directory), and the API matches what the CLI gives."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

import bsp_ros
from bsp_ros.cli import main

DOCS = Path(__file__).resolve().parents[1] / "docs" / "api.md"


def test_the_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    (example,) = re.findall(r"```python\n(.*?)```", DOCS.read_text(encoding="utf-8"), flags=re.S)
    monkeypatch.chdir(tmp_path)
    exec(compile(example, str(DOCS), "exec"), {})
    out = capsys.readouterr().out
    assert out.startswith("True identified from") and "stored session 1 of P001" in out
    assert (tmp_path / "session_a" / "truth.json").exists() and (tmp_path / "clinic.sqlite").exists()


def test_identify_gives_what_bsp_identify_writes(tmp_path: Path) -> None:
    bag = bsp_ros.simulate(tmp_path / "s", duration_s=30, seed=4)
    estimate = bsp_ros.identify(bag, marker_placement_sd_mm=1.0)
    assert main(["identify", str(bag), "--json", str(tmp_path / "e.json"), "--format", "none",
                 "--marker-placement-sd-mm", "1"]) == 0  # fmt: skip
    written = json.loads((tmp_path / "e.json").read_text())
    mine = json.loads(json.dumps(estimate.to_json()))
    for document in (written, mine):
        document["session"].pop("content_sha256", None)
    assert mine["segments"] == written["segments"] and mine["joints"] == written["joints"]
    truth = json.loads((bag / "truth.json").read_text())
    for record in bsp_ros.to_records(estimate):
        if record["quantity"] == "static_moment_kgm":
            true = truth["segments"][record["owner"]]["static_moment_kgm"]
            assert abs(record["value"] - true) < 3 * record["std"]
            assert sum(v**2 for k, v in record.items() if k.startswith("budget/")) == pytest.approx(record["std"] ** 2)


def test_import_is_light_and_unknown_names_fail() -> None:
    with pytest.raises(AttributeError):
        _ = bsp_ros.no_such_function
