"""`bsp identify --wrench-delay-s S`: a delay the cell knows is applied as given and reported; a bad one is refused."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bsp_ros.cli import main


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("delay") / "session"
    assert main(["simulate", "--out", str(path), "--subject", "human", "--duration", "40", "--seed", "5"]) == 0
    return path


def test_a_given_delay_is_applied_and_reported(bag: Path, tmp_path: Path) -> None:
    out = tmp_path / "estimate.json"
    args = ["identify", str(bag), "--json", str(out), "--format", "none", "--wrench-delay-s", "0.004"]
    assert main(args) == 0
    timing = json.loads(out.read_text())["quality"]["timing"]
    assert timing == {"wrench_delay_s": 0.004, "wrench_delay_std_s": 0.0, "source": "parameter"}
    # Without it the delay is estimated; this simulated session has none, so none is compensated.
    assert main(["identify", str(bag), "--json", str(out), "--format", "none"]) == 0
    quality = json.loads(out.read_text())["quality"]
    assert quality["timing"]["source"] == "none" and quality["timing"]["wrench_delay_s"] == 0.0
    assert abs(quality["timing"]["estimated_delay_s"]) <= 3 * quality["timing"]["estimated_delay_std_s"]
    assert quality["rotation"] == {"source": "tf", "per_sample": False, "range_deg": 0.0}


def test_a_delay_that_is_not_a_number_is_refused_naming_it(bag: Path, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as stop:  # argparse's usage error, exit code 2 (README, Exit codes)
        main(["identify", str(bag), "--wrench-delay-s", "nan"])
    assert stop.value.code == 2
    assert "argument --wrench-delay-s: must be a finite number within [-10, 10], got 'nan'" in capsys.readouterr().err
