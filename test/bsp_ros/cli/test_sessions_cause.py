"""`bsp sessions add` and `bsp sessions show` say why a stored session is not valid, in plain words."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_run import bsp

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
