"""`bsp sessions add` and `bsp sessions show` say why a stored session is not valid, in plain words."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_run import bsp

import bsp_ros
from bsp_ros.cli import main


@pytest.fixture(scope="module")
def one_way(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """4 s: the shoulder and wrist move one way only, an estimate that is stored but not valid."""
    bag = tmp_path_factory.mktemp("cause") / "one_way"
    assert main(["simulate", "--out", str(bag), "--duration", "4", "--seed", "1"]) == 0
    return bag


def test_the_cause_and_the_action_are_printed_when_stored_and_shown(
    one_way: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    store = str(tmp_path / "clinic.sqlite")
    code, out, _ = bsp(capsys, "sessions", "add", str(one_way), "--store", store, "--subject", "P001")
    assert code == 0 and "NOT VALID" in out
    expected = "  not valid: a joint moved in one direction only; repeat with the full back-and-forth movement ("
    assert any(line.startswith(expected) for line in out.splitlines()), out
    code, out, _ = bsp(capsys, "sessions", "show", "--store", store, "P001")
    assert code == 0 and any(line.startswith(expected) for line in out.splitlines()), out


def test_an_untared_session_among_tared_ones_is_warned_of(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    results = []
    for seed, (day, tared) in enumerate((("2026-01-05", True), ("2026-01-12", True), ("2026-01-19", False))):
        bag = bsp_ros.simulate(tmp_path / f"session_{seed}", duration_s=30, seed=seed)
        result = json.loads(json.dumps(bsp_ros.identify(bag).to_json()))
        assert result["quality"]["valid"]
        # As a tare would have marked it (its uncertainty aside, which the warning does not read).
        result["quality"]["tare"] = {"applied": tared, "file": "cell.tare.yaml" if tared else None}
        path = tmp_path / f"{day}.json"
        path.write_text(json.dumps(result))
        results.append((day, path))
    store = str(tmp_path / "clinic.sqlite")
    for day, path in results:
        code, _, err = bsp(capsys, "sessions", "add", str(path), "--store", store, "--subject", "P002", "--time", day)
        assert code == 0, err
    assert err.startswith("warning: session 3 of P002 has no tare while 2 of its sessions do")
    assert "bsp tare" in err


def test_sessions_show_json_carries_each_finding_with_its_cause_and_action(
    one_way: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from bsp_ros.core.findings import FindingCode
    from bsp_ros.core.findings_specs import SPECS

    store = str(tmp_path / "clinic.sqlite")
    assert bsp(capsys, "sessions", "add", str(one_way), "--store", store, "--subject", "P003")[0] == 0
    code, out, _ = bsp(capsys, "sessions", "show", "--store", store, "P003", "--json")
    assert code == 0
    (shown,) = json.loads(out)
    findings = shown["quality"]["findings"]
    first = next(f for f in findings if f["severity"] == "invalid")
    spec = SPECS[FindingCode.ONE_DIRECTION]
    assert first["code"] == "one_direction" and first["cause"] == spec.cause and first["action"] == spec.action
    assert first["text"] and isinstance(first["values"], dict) and "where" in first
    for finding in findings:
        assert set(finding) >= {"code", "severity", "where", "text", "values", "cause", "action"}
        assert bool(finding["cause"]) == bool(SPECS[FindingCode(finding["code"])].cause)
    # The shown session is an estimate document again: stored back, it keeps its findings.
    again = tmp_path / "shown.json"
    again.write_text(json.dumps(shown))
    assert bsp(capsys, "sessions", "add", str(again), "--store", store, "--subject", "P004")[0] == 0
    (back,) = json.loads(bsp(capsys, "sessions", "show", "--store", store, "P004", "--json")[1])
    assert back["quality"]["findings"] == findings
