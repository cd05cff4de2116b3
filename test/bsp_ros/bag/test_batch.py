"""Which bags a batch means (`bsp identify --each`): a rosbag2 directory is one bag, a folder of plain MCAP files
(no metadata.yaml) is one bag per file, and a folder of bags stands for the bags inside."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import pytest

from bsp_ros.bag.batch import bag_name, expand_bags
from bsp_ros.cli import main


def test_a_folder_expands_to_its_bags_and_its_plain_mcap_files_one_by_one(tmp_path: Path) -> None:
    (tmp_path / "study" / "rosbag").mkdir(parents=True)
    (tmp_path / "study" / "rosbag" / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    (tmp_path / "study" / "rosbag" / "rosbag_0.mcap").write_bytes(b"")
    for name in ("b.mcap", "a.mcap"):
        (tmp_path / "study" / name).write_bytes(b"")
    (tmp_path / "study" / "loose").mkdir()
    (tmp_path / "study" / "loose" / "c.mcap").write_bytes(b"")
    (tmp_path / "study" / "loose" / "d.mcap").write_bytes(b"")
    (tmp_path / "study" / "sqlite").mkdir()
    (tmp_path / "study" / "sqlite" / "x.db3").write_bytes(b"")
    (tmp_path / "study" / "notes").mkdir()
    (tmp_path / "study" / "notes" / "readme.txt").write_text("not a bag\n")
    (tmp_path / "empty").mkdir()
    study = tmp_path / "study"
    bags = expand_bags([study, tmp_path / "empty", tmp_path / "gone", study / "loose", study / "rosbag"])
    assert bags == [
        study / "a.mcap",
        study / "b.mcap",
        study / "loose" / "c.mcap",
        study / "loose" / "d.mcap",
        study / "rosbag",  # metadata.yaml: one bag, its files together
        study / "sqlite",  # a refused storage: one row, which says why
        tmp_path / "empty",  # no bag inside: kept, so its reading says so
        tmp_path / "gone",
        study / "loose" / "c.mcap",
        study / "loose" / "d.mcap",
        study / "rosbag",
    ]
    assert [bag_name(b) for b in bags[:5]] == ["a", "b", "c", "d", "rosbag"]


@pytest.fixture(scope="module")
def simulated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two 20 s simulated sessions of different arms, as rosbag2 directories."""
    where = tmp_path_factory.mktemp("batch")
    assert main(["simulate", "--out", str(where / "human"), "--duration", "20", "--seed", "1"]) == 0
    argv = ["simulate", "--out", str(where / "paper"), "--duration", "20", "--seed", "6", "--subject", "paper-arm"]
    assert main(argv) == 0
    return where


def test_each_identifies_a_folder_of_plain_mcap_files_file_by_file(
    simulated: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plain = tmp_path / "plain"
    plain.mkdir()
    for name in ("human", "paper"):
        (mcap,) = (simulated / name).glob("*.mcap")
        shutil.copy(mcap, plain / f"{name}.mcap")
    out = tmp_path / "out"
    argv = ["identify", "--each", str(plain), "--json-dir", str(out), "--summary", str(out / "s.csv")]
    assert main([*argv, "--passive", "coulomb"]) == 0
    capsys.readouterr()
    with open(out / "s.csv", newline="") as stream:
        rows = list(csv.DictReader(stream))
    assert [(Path(r["bag"]).name, r["exit_code"], r["json"]) for r in rows] == [
        ("human.mcap", "0", "human.json"),
        ("paper.mcap", "0", "paper.json"),
    ]
    # Each file alone is its recording: the estimate of the rosbag2 directory it came from, and its truth.
    for name in ("human", "paper"):
        alone = json.loads((out / f"{name}.json").read_text())
        assert (
            main(["identify", str(simulated / name), "--passive", "coulomb", "--json", str(tmp_path / "d.json")]) == 0
        )
        directory = json.loads((tmp_path / "d.json").read_text())
        assert alone["segments"] == directory["segments"] and alone["joints"] == directory["joints"]
        truth = json.loads((simulated / name / "truth.json").read_text())
        for segment, quantities in alone["segments"].items():
            moment = quantities["static_moment_kgm"]
            assert abs(moment["value"] - truth["segments"][segment]["static_moment_kgm"]) < 3 * moment["std"]
    capsys.readouterr()


def test_bags_that_are_not_one_arms_recordings_point_to_each(
    simulated: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    human, paper = simulated / "human", simulated / "paper"
    for bags, cause in (([human, human], "overlap in time"), ([human, paper], "different numbers of segments")):
        assert main(["identify", *map(str, bags), "--json", str(tmp_path / "x.json")]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("bsp identify: error: ") and cause in err
        assert "each bag its own session: bsp identify --each BAG... --json-dir DIR --summary FILE" in err
    # One bag's refusal needs no such hint.
    assert main(["identify", str(human), "--marker-topic", "knee=/k", "--format", "none"]) == 2
    assert "--each" not in capsys.readouterr().err
