"""docs/api.md's example runs as written (in a fresh directory), and the API matches what the CLI gives."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import types
from pathlib import Path

import pytest
import yaml

import bsp_ros
from bsp_ros.bag.errors import MissingTopicError
from bsp_ros.cli import main
from bsp_ros.errors import InputError

DOCS = Path(__file__).resolve().parents[1] / "docs" / "api.md"
CELL = Path(__file__).resolve().parents[1] / "bsp_ros" / "config" / "cell.yaml"


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
    # A fresh interpreter: `import bsp_ros` loads neither the estimator's numerics nor the API module.
    script = (
        "import sys, bsp_ros; print(sorted(m for m in sys.modules if m.split('.')[0] in HEAVY or m == 'bsp_ros.api'))"
    )
    heavy = ("numpy", "scipy", "rclpy", "rosbags", "mcap", "pandas", "yaml")
    done = subprocess.run(
        [sys.executable, "-c", f"HEAVY = {heavy!r}\n{script}"], capture_output=True, text=True, timeout=60, check=True
    )
    assert done.stdout.strip() == "[]", done.stdout
    done = subprocess.run(
        [sys.executable, "-c", "import bsp_ros, sys; bsp_ros.to_records; print('numpy' in sys.modules)"],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    assert done.stdout.strip() == "False"  # the API module itself is light: identify loads the estimator


@pytest.fixture(scope="module")
def short_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 20 s simulated session (seed 3) with its truth."""
    return bsp_ros.simulate(tmp_path_factory.mktemp("api") / "short", duration_s=20, seed=3)


def test_identify_takes_the_bag_positionally_or_by_name_and_the_clis_topic_options(short_bag: Path) -> None:
    by_position = bsp_ros.identify(
        short_bag, handle_pose_topic="", emg_topic="", marker_topics={"elbow": "/mocap/elbow"}
    )
    by_name = bsp_ros.identify(bag_or_bags=[str(short_bag)])
    assert by_position.valid and by_position.to_json()["segments"] == by_name.to_json()["segments"]
    truth = json.loads((short_bag / "truth.json").read_text())
    for segment, quantities in by_position.segments.items():
        moment = quantities["static_moment_kgm"]
        assert abs(moment.value - truth["segments"][segment]["static_moment_kgm"]) < 3 * moment.std, segment


def test_identify_reads_the_topics_it_is_told_and_the_cells(short_bag: Path, tmp_path: Path) -> None:
    with pytest.raises(MissingTopicError) as raised:
        bsp_ros.identify(short_bag, wrench_topic="/force")
    assert raised.value.code == "missing-topic" and "/force" in str(raised.value)
    cell = yaml.safe_load(CELL.read_text())
    cell["ft_sensor"]["wrench_topic"] = "/cell/force"
    (tmp_path / "cell.yaml").write_text(yaml.safe_dump(cell))
    with pytest.raises(MissingTopicError, match="/cell/force") as raised:
        bsp_ros.identify(short_bag, cell=tmp_path / "cell.yaml")
    assert raised.value.code == "missing-topic"
    # As `bsp identify --cell FILE` reads it.
    assert main(["identify", str(short_bag), "--cell", str(tmp_path / "cell.yaml"), "--format", "none"]) == 13


@pytest.mark.parametrize(
    ("options", "said"),
    [
        ({"marker_placement_sd_mm": -1.0}, "--marker-placement-sd-mm"),
        ({"sex": "other"}, "--sex"),
        ({"method": "fast"}, "--method"),
        ({"passive": "coulomb+springs"}, "--passive coulomb+springs"),
        ({"marker_topics": {"knee": "/mocap/knee"}}, "--marker-topic"),
        ({"trunk_tilt_deg": [0.0, 25.0]}, "--trunk-tilt-deg gives 2 tilts"),
    ],
)
def test_a_bad_option_is_an_input_error_naming_it(short_bag: Path, options: dict[str, object], said: str) -> None:
    with pytest.raises(InputError, match=re.escape(said)):
        bsp_ros.identify(short_bag, **options)


def test_to_frame_passes_every_record_with_its_label(short_bag: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    estimate = bsp_ros.identify(short_bag)
    given: list[list[dict[str, object]]] = []
    try:
        import pandas  # noqa: F401
    except ImportError:  # pandas is optional: a stand-in module takes what to_frame passes to DataFrame

        def data_frame(rows: list[dict[str, object]]) -> str:
            given.append(rows)
            return "frame"

        stand_in = types.ModuleType("pandas")
        stand_in.DataFrame = data_frame  # type: ignore[attr-defined]
        monkeypatch.setitem(sys.modules, "pandas", stand_in)

    def rows_of(frame: object) -> list[dict[str, object]]:
        return given.pop() if given else frame.to_dict("records")  # type: ignore[attr-defined]

    records = bsp_ros.to_records(estimate)
    rows = rows_of(bsp_ros.to_frame([estimate, estimate], labels=["before", "after"]))
    assert len(rows) == 2 * len(records) > 10
    assert [r["label"] for r in rows] == ["before"] * len(records) + ["after"] * len(records)
    for row, record in zip(rows, [*records, *records], strict=True):
        assert set(row) >= {"label", "group", "owner", "quantity", "value", "std", "source", "valid"}
        assert all(row[k] == record[k] for k in ("group", "owner", "quantity", "source", "valid"))
        assert row["value"] == pytest.approx(record["value"]) and row["std"] == pytest.approx(record["std"])
    # One estimate: labelled by its recording's name.
    assert {r["label"] for r in rows_of(bsp_ros.to_frame(estimate))} == {short_bag.name}
