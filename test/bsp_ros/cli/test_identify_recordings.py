"""`bsp identify BAG1 BAG2 --trunk-tilt-deg 0 25`: two postures of one arm, simulated by `bsp simulate`."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bsp_ros.cli import main

SPRINGS = ["--stiffness", "0.5", "0.3", "0.05", "--neutral", "-0.7557", "0.5149", "0", "--duration", "90"]


@pytest.fixture(scope="module")
def postures(tmp_path_factory) -> tuple[Path, Path]:
    where = tmp_path_factory.mktemp("postures")
    assert main(["simulate", "--out", str(where / "upright"), "--seed", "3", *SPRINGS]) == 0
    tilted = ["--trunk-tilt-deg", "25", "--start-offset-s", "300"]
    assert main(["simulate", "--out", str(where / "tilted"), "--seed", "4", *SPRINGS, *tilted]) == 0
    return where / "upright", where / "tilted"


def _identify(bags: list[Path], out: Path, *extra: str) -> tuple[int, dict]:
    argv = [
        "identify",
        *map(str, bags),
        "--passive",
        "coulomb+offset+stiffness",
        "--json",
        str(out),
        "--format",
        "none",
    ]
    code = main([*argv, *extra])
    return code, json.loads(out.read_text()) if out.exists() else {}


def test_two_postures_identify_the_arm_and_say_what_they_combined(postures, tmp_path) -> None:
    upright, tilted = postures
    truth = json.loads((upright / "truth.json").read_text())
    _, alone = _identify([upright], tmp_path / "alone.json")
    code, both = _identify([upright, tilted], tmp_path / "both.json", "--trunk-tilt-deg", "0", "25")
    assert code == 0, both["quality"]["message"]
    for segment in ("upper_arm", "forearm", "hand"):
        q, true = both["segments"][segment]["static_moment_kgm"], truth["segments"][segment]["static_moment_kgm"]
        assert abs(q["value"] - true) < 3 * q["std"], segment
    std = [d["segments"]["upper_arm"]["static_moment_kgm"]["std"] for d in (alone, both)]
    assert std[1] < std[0] / 2.5, std
    session = both["session"]
    assert session["source"] == "upright + tilted"
    assert [(r["source"], r["trunk_tilt_deg"]) for r in session["recordings"]] == [("upright", 0.0), ("tilted", 25.0)]
    assert [len(b["files"]) for b in both["bags"]] == [1, 1] and "bag" not in both
    assert session["content_sha256"] not in {r["content_sha256"] for r in session["recordings"]}


def test_tilts_that_do_not_match_the_bags_are_refused_with_the_values(postures, tmp_path, capsys) -> None:
    upright, tilted = postures
    code, _ = _identify([upright, tilted], tmp_path / "x.json", "--trunk-tilt-deg", "25")
    assert code == 2
    assert "--trunk-tilt-deg gives 1 tilts (25) for 2 recordings" in capsys.readouterr().err
    code, _ = _identify([upright, tilted], tmp_path / "x.json", "--trunk-tilt-deg", "0", "95")
    assert code == 2
    assert "--trunk-tilt-deg 95" in capsys.readouterr().err
    code, _ = _identify([upright, upright], tmp_path / "x.json")
    assert code == 2
    assert "overlap in time" in capsys.readouterr().err
