"""What `bsp identify` prints for a newcomer and a script: its TSV, why an estimate is invalid, bad --tare files."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.cli import main
from bsp_ros.cli.identify import TSV_HEADER

INVALID, BAD_OPTION, DATA, CORRUPT = 1, 2, 3, 15


def _simulate(root: Path, name: str, *options: str) -> Path:
    bag = root / name
    assert main(["simulate", "--out", str(bag), *options]) == 0
    return bag


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    root = tmp_path_factory.mktemp("identify_output")
    return {
        "session": _simulate(root, "session", "--duration", "10", "--seed", "3"),
        # 4 s: the shoulder and wrist move one way only, an estimate that is written but invalid.
        "one_way": _simulate(root, "one_way", "--duration", "4", "--seed", "1"),
        "tare": _simulate(root, "tare_rec", "--tare", "--duration", "6", "--seed", "3"),
    }


def test_the_tsv_has_a_header_and_five_columns_on_every_row(
    bags: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "e.json"
    code = main(["identify", str(bags["session"]), "--json", str(out), "--format", "tsv"])
    document = json.loads(out.read_text())
    lines = capsys.readouterr().out.splitlines()
    table = [line.split("\t") for line in lines]
    assert code == 0
    assert tuple(table[0]) == TSV_HEADER
    assert {len(row) for row in table} == {5}
    assert "None" not in "\n".join(lines) and "nan" not in "\n".join(lines)
    quality = {row[1]: row[2] for row in table if row[0] == "quality"}
    assert quality["valid"] == "true"
    assert quality["message"] == document["quality"]["message"]
    assert quality["tare"].startswith("none applied") and "bsp tare" in quality["tare"]
    values = {(row[0], row[1]): row for row in table[1:] if row[0] != "quality"}
    for group in ("segments", "joints"):
        for owner, quantities in document[group].items():
            for key, q in quantities.items():
                _, _, value, std, source = values.pop((owner, key))
                assert (float(value) if value else None) == q["value"]
                assert (float(std) if std else None) == q["std"]
                assert source == q["source"]
    assert values == {}


def test_an_invalid_estimate_says_why_on_stderr_even_with_format_none(
    bags: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "e.json"
    code = main(["identify", str(bags["one_way"]), "--json", str(out), "--format", "none"])
    captured = capsys.readouterr()
    quality = json.loads(out.read_text())["quality"]
    assert code == INVALID
    assert captured.out == ""
    # The cause in plain words and what to do, then each reason the estimator found.
    reasons = [f["text"] for f in quality["findings"] if f["severity"] == "invalid"]
    assert [f["code"] for f in quality["findings"][: len(reasons)]] == ["one_direction"] * len(reasons)
    assert captured.err.splitlines() == [
        "bsp identify: estimate INVALID: a joint moved in one direction only; repeat with the full back-and-forth "
        "movement",
        *(f"  because: {reason}" for reason in reasons),
    ]


@pytest.mark.parametrize("duration_s", ["0.5", "2"])
def test_too_few_samples_is_one_rule_exit_3_and_no_estimate(
    duration_s: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # 0.5 s fails while the joint angles are computed, 2 s (98 samples) at the estimator's 200: both exit 3.
    bag = _simulate(tmp_path, "short", "--duration", duration_s, "--seed", "1")
    capsys.readouterr()
    out = tmp_path / "e.json"
    code = main(["identify", str(bag), "--json", str(out), "--format", "none"])
    err = capsys.readouterr().err
    assert code == DATA
    assert err.startswith("bsp identify: error: ") and err.count("\n") == 1
    assert not out.exists()


def test_a_tare_recording_given_as_the_tare_file_says_how_to_make_the_file(
    bags: dict[str, Path], capsys: pytest.CaptureFixture[str]
) -> None:
    tare = bags["tare"]
    for given in (tare, next(tare.glob("*.mcap"))):
        code = main(["identify", str(bags["session"]), "--tare", str(given), "--format", "none"])
        err = capsys.readouterr().err
        assert code == BAD_OPTION
        assert f"--tare {given} is a recording (a bag)" in err
        assert f"`bsp tare {given} --out FILE`" in err


def test_the_tare_file_made_as_the_message_says_is_then_accepted(
    bags: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tare_file = tmp_path / "cell.tare.yaml"
    assert main(["tare", str(bags["tare"]), "--out", str(tare_file)]) == 0
    out = tmp_path / "e.json"
    assert (
        main(["identify", str(bags["session"]), "--tare", str(tare_file), "--json", str(out), "--format", "none"]) == 0
    )
    assert json.loads(out.read_text())["quality"]["tare"]["applied"] is True


@pytest.mark.parametrize(("content", "expected"), [("- a\n- b\n", "holds a mapping"), ("{", "is not YAML")])
def test_a_tare_file_that_is_not_a_tare_names_the_file(
    content: str, expected: str, bags: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text(content)
    code = main(["identify", str(bags["session"]), "--tare", str(bad), "--format", "none"])
    err = capsys.readouterr().err
    assert code == BAD_OPTION
    assert err.startswith(f"bsp identify: error: --tare {bad}: ") and expected in err


def test_a_corrupt_bag_gives_the_count_and_the_first_damaged_place(
    bags: dict[str, Path], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    damaged = tmp_path / "damaged"
    shutil.copytree(bags["session"], damaged)
    mcap = next(damaged.glob("*.mcap"))
    data = bytearray(mcap.read_bytes())
    for at in range(200, len(data) - 200, 997):  # damage in every chunk: no wrench message survives
        data[at] ^= 0xFF
    mcap.write_bytes(bytes(data))
    code = main(["identify", str(damaged), "--format", "none"])
    err = capsys.readouterr().err
    assert code == CORRUPT
    assert err.count("\n") == 1 and len(err) < 400
    assert "damaged places, the first: " in err and "CRC errors" in err


def test_a_session_with_springs_prints_its_passive_curves_in_the_tsv(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # Elastic terms chosen by the data write joints.<joint>.passive_curve, which is not a quantity: the TSV
    # once crashed on it (KeyError 'value'), whatever the passive option that chose them.
    bag = _simulate(
        tmp_path,
        "springs",
        "--duration",
        "30",
        "--seed",
        "4",
        "--stiffness",
        "0.3",
        "0.5",
        "0",
        "--passive-offset",
        "0.1",
        "0.2",
        "0",
    )
    capsys.readouterr()
    out = tmp_path / "e.json"
    assert main(["identify", str(bag), "--passive", "auto", "--json", str(out), "--format", "tsv"]) == 0
    document = json.loads(out.read_text())
    table = [line.split("\t") for line in capsys.readouterr().out.splitlines()]
    assert {len(row) for row in table} == {5}
    curves = {j: q["passive_curve"] for j, q in document["joints"].items() if "passive_curve" in q}
    assert "elbow" in curves
    for joint, curve in curves.items():
        printed = [row for row in table if row[0] == joint and row[1].startswith("passive_moment_nm@")]
        assert [float(row[1].split("@")[1].removesuffix("deg")) for row in printed] == pytest.approx(
            curve["angle_deg"], abs=0.051
        )
        assert [float(row[2]) for row in printed] == curve["moment_nm"]
        assert [float(row[3]) for row in printed] == curve["std_nm"]
        (stiffness,) = [row for row in table if row[0] == joint and row[1].startswith("passive_stiffness")]
        assert float(stiffness[2]) == curve["stiffness_nm_per_rad"]
    # The simulated elbow spring (offset 0.2 Nm + 0.5 Nm/rad from neutral 0) lies within 3 std of its curve.
    elbow = curves["elbow"]
    truth = 0.2 + 0.5 * np.radians(elbow["angle_deg"])
    assert np.all(np.abs(np.array(elbow["moment_nm"]) - truth) <= 3 * np.array(elbow["std_nm"]))
