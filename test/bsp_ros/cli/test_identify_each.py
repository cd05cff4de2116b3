"""`bsp identify --each`: every bag its own session, against simulated bags with known truth and broken ones."""

from __future__ import annotations

import csv
import io
import json
import os
import shutil
from pathlib import Path

import pytest

from bsp_ros.cli import main
from bsp_ros.cli.identify_each import BagRow, BagTask, Progress, row_of, run_tasks
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.methods import Method

# Coulomb only: the stiff arm's elastic moment then makes its estimate invalid (the others stay valid).
PASSIVE = ["--passive", "coulomb"]
SHORT = ["--duration", "20"]


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A folder of five bags: two valid arms (human, paper arm), one with springs the model lacks, one cut so short
    that no stretch of markers survives, one cut inside its first record."""
    where = tmp_path_factory.mktemp("each") / "bags"
    assert main(["simulate", "--out", str(where / "a_arm"), "--seed", "1", *SHORT]) == 0
    assert main(["simulate", "--out", str(where / "b_paper"), "--seed", "6", "--subject", "paper-arm", *SHORT]) == 0
    springs = ["--stiffness", "3", "2", "0.5"]
    assert main(["simulate", "--out", str(where / "c_stiff"), "--seed", "5", *springs, *SHORT]) == 0
    for name, size in (("d_cut", 100_000), ("e_corrupt", 3_000)):
        shutil.copytree(where / "a_arm", where / name)
        (mcap,) = (where / name).glob("*.mcap")
        os.truncate(mcap, size)
    (where.parent / "notes").mkdir()
    (where.parent / "notes" / "readme.txt").write_text("not a bag\n")
    return where


def _number(cell: str) -> float | None:
    return None if cell == "" else float(cell)


def _each(bags: Path, out: Path, *extra: str) -> tuple[int, list[dict[str, str]]]:
    argv = ["identify", "--each", str(bags), str(bags.parent / "notes"), *PASSIVE]
    code = main([*argv, "--json-dir", str(out / "json"), "--summary", str(out / "summary.csv"), *extra])
    with open(out / "summary.csv", newline="") as stream:
        return code, list(csv.DictReader(stream))


def test_each_bag_has_its_json_and_row_with_the_code_it_alone_gives(bags: Path, tmp_path: Path, capsys) -> None:
    code, rows = _each(bags, tmp_path)
    assert code == 1  # not every bag gave a valid estimate
    names = ["a_arm", "b_paper", "c_stiff", "d_cut", "e_corrupt", "notes"]
    assert [Path(r["bag"]).name for r in rows] == names
    assert [int(r["exit_code"]) for r in rows] == [0, 0, 1, 3, 15, 11]
    for row in rows:  # each the code `bsp identify BAG` alone exits with
        assert main(["identify", row["bag"], *PASSIVE, "--format", "none"]) == int(row["exit_code"]), row["bag"]
    capsys.readouterr()
    assert [r["valid"] for r in rows] == ["1", "1", "0", "", "", ""]
    lacking = Finding(code=FindingCode.ELASTIC_LACKING)
    assert (rows[2]["cause_code"], rows[2]["cause"]) == ("elastic_lacking", lacking.spec.cause)
    assert "no stretch of marker data" in rows[3]["cause"]
    assert "no intact message survives" in rows[4]["cause"] and "not a bag" in rows[5]["cause"]
    assert sorted(p.name for p in (tmp_path / "json").iterdir()) == ["a_arm.json", "b_paper.json", "c_stiff.json"]
    truth = json.loads((bags / "a_arm" / "truth.json").read_text())
    for row in rows[:3]:
        document = json.loads((tmp_path / "json" / row["json"]).read_text())
        assert row["content_sha256"] == document["session"]["content_sha256"]
        assert float(row["duration_s"]) == document["session"]["duration_s"]
        assert row["passive_model"] == document["diagnostics"]["passive_model"] == "coulomb"
        assert row["tare_applied"] == "0"
        for owner, entries in [*document["segments"].items(), *document["joints"].items()]:
            for key, q in entries.items():
                if key in ("static_moment_kgm", "mass_kg", "coulomb_nm"):
                    assert _number(row[f"{key}/{owner}"]) == q["value"], (row["bag"], key, owner)
                    assert _number(row[f"{key}/{owner}_std"]) == q["std"], (row["bag"], key, owner)
    arm = rows[0]
    for segment in ("upper_arm", "forearm", "hand"):
        error = float(arm[f"static_moment_kgm/{segment}"]) - truth["segments"][segment]["static_moment_kgm"]
        assert abs(error) < 3 * float(arm[f"static_moment_kgm/{segment}_std"]), segment
    # The paper arm has no hand and no wrist: its cells there are empty, the columns are the human arm's.
    assert rows[1]["static_moment_kgm/hand"] == "" and rows[1]["coulomb_nm/wrist"] == ""


def test_two_workers_give_the_rows_of_one(bags: Path, tmp_path: Path) -> None:
    one, two = tmp_path / "one", tmp_path / "two"
    assert _each(bags, one, "--jobs", "1")[0] == _each(bags, two, "--jobs", "2")[0] == 1
    assert (one / "summary.csv").read_text() == (two / "summary.csv").read_text()
    for name in ("a_arm.json", "c_stiff.json"):
        assert (one / "json" / name).read_text() == (two / "json" / name).read_text()


def test_every_bag_valid_exits_0_and_a_summary_on_stdout(bags: Path, tmp_path: Path, capsys) -> None:
    argv = ["identify", "--each", str(bags / "a_arm"), str(bags / "b_paper"), "--json-dir", str(tmp_path)]
    assert main([*argv, "--summary", "-"]) == 0
    out = capsys.readouterr().out
    rows = list(csv.DictReader(out.splitlines()))
    assert [(Path(r["bag"]).name, r["exit_code"], r["json"]) for r in rows] == [
        ("a_arm", "0", "a_arm.json"),
        ("b_paper", "0", "b_paper.json"),
    ]


@pytest.mark.parametrize(
    ("extra", "said"),
    [
        (["--each", "--summary", "s.csv"], "--each needs --json-dir"),
        (["--each", "--json-dir", "j"], "--each needs --summary"),
        (["--json-dir", "j"], "--json-dir goes with --each"),
        (["--each", "--json-dir", "j", "--summary", "s.csv", "--json", "x.json"], "--json is one estimate"),
        (["--each", "--json-dir", "j", "--summary", "s.csv", "--format", "tsv"], "--format tsv"),
    ],
)
def test_usage_errors_exit_2(bags: Path, tmp_path: Path, capsys, monkeypatch, extra: list[str], said: str) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["identify", str(bags / "a_arm"), *extra]) == 2
    err = capsys.readouterr().err
    assert said in err and err.count("\n") == 1 and not list(tmp_path.iterdir())


def test_two_bags_of_one_name_are_refused(bags: Path, tmp_path: Path, capsys) -> None:
    shutil.copytree(bags / "a_arm", tmp_path / "other" / "a_arm")
    argv = ["identify", "--each", str(bags / "a_arm"), str(tmp_path / "other" / "a_arm")]
    assert main([*argv, "--json-dir", str(tmp_path / "j"), "--summary", str(tmp_path / "s.csv")]) == 2
    assert "two bags named a_arm" in capsys.readouterr().err


def test_json_dash_is_the_estimate_alone_on_stdout(bags: Path, tmp_path: Path, capsys, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    bag = str(bags / "a_arm")
    assert main(["identify", bag, "--json", str(tmp_path / "a.json"), "--format", "none"]) == 0
    capsys.readouterr()
    for fmt in ("none", "auto"):
        assert main(["identify", bag, "--json", "-", "--format", fmt]) == 0
        out = capsys.readouterr().out
        assert json.loads(out) == json.loads((tmp_path / "a.json").read_text())
    assert not Path("-").exists()
    assert main(["identify", bag, "--json", "-", "--format", "tsv"]) == 2
    assert "--json - writes the estimate to stdout" in capsys.readouterr().err


class _KillsItsWorker:
    """Unpickled in a worker, it ends that process at once, as the system's out-of-memory killer would."""

    def __reduce__(self) -> tuple[object, tuple[int]]:
        return os._exit, (9,)


def test_a_worker_that_dies_costs_only_its_own_bag(bags: Path, tmp_path: Path) -> None:
    from bsp_ros.core.pipeline import IdentifyOptions

    fine = BagTask(0, str(bags / "a_arm"), str(tmp_path / "a_arm.json"), IdentifyOptions(), None, None)
    deadly = BagTask(1, str(bags / "b_paper"), str(tmp_path / "b_paper.json"), _KillsItsWorker(), None, None)
    rows: list[BagRow] = []
    run_tasks([fine, deadly], 2, rows.append)
    by_index = {row.index: row for row in rows}
    assert sorted(by_index) == [0, 1] and len(rows) == 2
    assert by_index[0].exit_code == 0 and by_index[0].json == "a_arm.json"
    assert by_index[1].exit_code == 1 and "worker process died" in by_index[1].cause


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_is_one_line_rewritten_on_a_terminal_and_nothing_elsewhere() -> None:
    terminal, pipe = _Terminal(), io.StringIO()
    for stream in (terminal, pipe):
        progress = Progress(2, stream)
        progress(BagRow(index=0, bag="a", exit_code=0))
        progress(BagRow(index=1, bag="b", exit_code=15))
    assert terminal.getvalue() == "\ridentify --each: 1/2 bags, 0 not valid\ridentify --each: 2/2 bags, 1 not valid\n"
    assert pipe.getvalue() == ""


def test_a_row_names_the_joint_its_cause_is_at() -> None:
    still = Finding(code=FindingCode.NO_MOTION, where="upper_arm", values={"range_deg": 0.01, "min_range_deg": 2.0})
    row = row_of(0, "day1", Estimate.invalid(Method.JOINT, still).to_json())
    assert (row.exit_code, row.cause_code, row.cause) == (3, "no_motion", "the upper arm did not move")
