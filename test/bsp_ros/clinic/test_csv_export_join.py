"""The sessions CSV's join columns: a stored session's rows lead back to its bag's row of `bsp identify --each`."""

from __future__ import annotations

import csv
import io
from pathlib import Path

import bsp_ros
from bsp_ros.cli import main
from bsp_ros.clinic.store import CSV_COLUMNS, open_store, write_sessions_csv
from bsp_ros.clinic.store.csv_export import JOIN_COLUMNS


def test_a_stored_session_joins_back_to_its_bag(tmp_path: Path, capsys) -> None:
    bag, store = tmp_path / "bags" / "day1", str(tmp_path / "clinic.sqlite")
    assert main(["simulate", "--out", str(bag), "--duration", "20", "--seed", "11"]) == 0
    argv = ["identify", "--each", str(bag.parent), "--json-dir", str(tmp_path / "json")]
    assert main([*argv, "--summary", str(tmp_path / "summary.csv"), "--passive", "coulomb+viscous"]) == 0
    assert main(["sessions", "add", str(tmp_path / "json" / "day1.json"), "--store", store, "--subject", "S001"]) == 0
    capsys.readouterr()
    with open(tmp_path / "summary.csv", newline="") as stream:
        (summary,) = csv.DictReader(stream)
    with open_store(store) as opened:
        stream = io.StringIO()
        count = write_sessions_csv(opened.sessions(), stream)
    rows = list(csv.DictReader(io.StringIO(stream.getvalue())))
    assert tuple(rows[0]) == CSV_COLUMNS and CSV_COLUMNS[-len(JOIN_COLUMNS) :] == JOIN_COLUMNS
    assert count == len(rows) > 0
    for row in rows:
        assert row["session_source"] == Path(summary["bag"]).name == "day1"
        assert row["content_sha256"] == summary["content_sha256"] != ""
        assert row["passive_model_configured"] == summary["passive_model"] == "coulomb+viscous"
        assert row["tare_applied"] == summary["tare_applied"] == "0" and row["tare_file"] == ""
        assert row["estimate_schema"] == "bsp_ros/core/estimate/1"
        assert row["bsp_ros_version"] == bsp_ros.__version__
    elbow = next(r for r in rows if (r["part"], r["quantity"]) == ("elbow", "viscous_nms"))
    assert float(elbow["value"]) == float(summary["viscous_nms/elbow"])
