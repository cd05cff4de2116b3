"""`bsp sessions export` joins back to `bsp identify --each`: every export row finds its bag's summary row by the
recording's name and content hash, and the two agree on the passive model used, the tare and each parameter.

Three simulated bags with known truth: two arms whose passive moment is Coulomb friction alone, and one with
joint springs, which the default passive model (Coulomb, with the elastic fallback) identifies with the elastic
model the data choose; so its passive model used differs from the one configured.
"""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import pytest

import bsp_ros
from bsp_ros.cli import main

BAGS = {
    "day1": ("1", []),
    "day2": ("2", []),
    "stiff": ("5", ["--stiffness", "3", "2", "0.5"]),
}


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="", encoding="utf-8") as stream:
        return list(csv.DictReader(stream))


@pytest.fixture(scope="module")
def exported(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[dict[str, str]], list[dict[str, str]]]:
    """The bags' folder, the `--each` summary rows and the `sessions export` rows of the bags stored one by one."""
    where = tmp_path_factory.mktemp("joins")
    bags, store = where / "bags", str(where / "clinic.sqlite")
    for name, (seed, extra) in BAGS.items():
        assert main(["simulate", "--out", str(bags / name), "--duration", "20", "--seed", seed, *extra]) == 0
    for name in BAGS:
        argv = ["sessions", "add", str(bags / name), "--store", store, "--subject", "S001", "--body-mass", "75"]
        assert main(argv) == 0
    argv = ["identify", "--each", str(bags), "--json-dir", str(where / "json"), "--summary", str(where / "s.csv")]
    assert main([*argv, "--body-mass", "75", "--format", "none"]) in (0, 1)
    assert main(["sessions", "export", "--store", store, "--csv", str(where / "export.csv")]) == 0
    return bags, _rows(where / "s.csv"), _rows(where / "export.csv")


def test_every_export_row_joins_its_bags_summary_row(
    exported: tuple[Path, list[dict[str, str]], list[dict[str, str]]],
) -> None:
    bags, summary, export = exported
    by_key = {(Path(r["bag"]).name, r["content_sha256"]): r for r in summary}
    assert len(by_key) == len(summary) == len(BAGS)
    joined: dict[str, int] = {}
    for row in export:
        each = by_key[(row["session_source"], row["content_sha256"])]  # a KeyError is a row that does not join
        joined[row["session_source"]] = joined.get(row["session_source"], 0) + 1
        assert row["valid"] == each["valid"] and row["tare_applied"] == each["tare_applied"] == "0"
        assert row["passive_model"] == each["passive_model"] != ""
        assert row["bsp_ros_version"] == bsp_ros.__version__
        column = f"{row['quantity']}/{row['part']}"
        if column in each:  # the summary's parameters: static moments, masses, passive parameters
            assert float(row["value"]) == float(each[column]), (row["session_source"], column)
            assert float(row["std"]) == float(each[f"{column}_std"]), (row["session_source"], column)
    assert set(joined) == set(BAGS) and all(n > 5 for n in joined.values())
    # The joined values are the truth's, within their std (the simulated arms' static moments).
    for row in export:
        if row["quantity"] == "static_moment_kgm" and row["valid"] == "1":
            truth = json.loads((bags / row["session_source"] / "truth.json").read_text())
            true = truth["segments"][row["part"]]["static_moment_kgm"]
            assert abs(float(row["value"]) - true) < 3 * float(row["std"]), (row["session_source"], row["part"])


def test_the_export_says_the_passive_model_used_beside_the_configured_one(
    exported: tuple[Path, list[dict[str, str]], list[dict[str, str]]],
) -> None:
    _, summary, export = exported
    used = {r["session_source"]: (r["passive_model_configured"], r["passive_model"]) for r in export}
    assert used["day1"] == used["day2"] == ("coulomb", "coulomb")
    configured, stiff = used["stiff"]
    # The springs the Coulomb model lacks: the fallback identified them with an elastic model of the data's choice.
    assert configured == "coulomb" and stiff.startswith("coulomb+") and "stiffness" in stiff
    assert "stiffness_nm_per_rad" in {r["quantity"] for r in export if r["session_source"] == "stiff"}
    assert next(r for r in summary if Path(r["bag"]).name == "stiff")["passive_model"] == stiff


def test_the_contract_lists_every_column_in_order() -> None:
    from bsp_ros.cli.identify_each import HEAD_COLUMNS, TAIL_COLUMNS
    from bsp_ros.clinic.report.export import CSV_COLUMNS

    text = (Path(__file__).resolve().parents[3] / "docs" / "contract.md").read_text(encoding="utf-8")
    section = text.split("## 12. Tables", 1)[1]
    summary, export = section.split("**`bsp sessions export --csv`**", 1)
    listed = [re.findall(r"`([a-z0-9_<>/]+)`", cell) for cell in re.findall(r"^\| (.+?) \|", summary, flags=re.M)]
    named = [name for names in listed for name in names if "<" not in name and name != "column"]
    assert named == [*HEAD_COLUMNS, *TAIL_COLUMNS]
    prose, table = export.split("then the join columns:", 1)
    joined = [re.findall(r"`([a-z0-9_]+)`", cell) for cell in re.findall(r"^\| (.+?) \|", table, flags=re.M)]
    columns = [*re.findall(r"`([a-z0-9_]+)`", prose), *(name for names in joined for name in names)]
    assert columns == list(CSV_COLUMNS)
