"""Bad input at the edges of `bsp`: one clear error line naming the value, a documented exit code, no traceback."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from bsp_ros.cli import main

# The README's "Exit codes" table.
BAD_OPTION, BAG_WRITE, STORE, WRONG_TYPE = 2, 4, 5, 14


@pytest.fixture(scope="module")
def bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("bags") / "session_edges"
    assert main(["simulate", "--out", str(path), "--duration", "10", "--seed", "3"]) == 0
    return path


def _one_error_line(err: str, command: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert "Traceback" not in err
    assert lines[-1].startswith(f"bsp {command}: error: ")
    return lines[-1]


def test_a_pose_topic_given_as_the_wrench_topic_is_a_wrong_message_type(
    bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "e.json"
    code = main(["identify", str(bag), "--wrench-topic", "/mocap/hand", "--json", str(out), "--format", "none"])
    line = _one_error_line(capsys.readouterr().err, "identify")
    assert code == WRONG_TYPE
    assert "/mocap/hand" in line and "PoseStamped" in line and "WrenchStamped" in line
    assert not out.exists()


def test_a_marker_topic_remapped_onto_the_wrench_topic_is_a_bad_option(
    bag: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main(["identify", str(bag), "--marker-topic", "hand=/ft_sensor/wrench", "--format", "none"])
    line = _one_error_line(capsys.readouterr().err, "identify")
    assert code == BAD_OPTION
    assert "hand=/ft_sensor/wrench" in line


@pytest.mark.parametrize("where", ["under_a_file", "proc", "directory", "proc_file"])
def test_an_unwritable_json_path_is_refused_before_the_bag_is_read(
    where: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "plain").write_text("a regular file\n")
    target = {
        "under_a_file": tmp_path / "plain" / "e.json",
        "proc": Path("/proc/bsp_edges_e.json"),
        "directory": tmp_path,
        "proc_file": Path("/proc/version"),
    }[where]
    # The bag does not exist: a check made after reading would exit 10 (no such path) instead.
    code = main(["identify", str(tmp_path / "no_bag"), "--json", str(target)])
    line = _one_error_line(capsys.readouterr().err, "identify")
    assert code == BAD_OPTION
    assert f"--json {target}" in line
    assert (tmp_path / "plain").read_text() == "a regular file\n"


@pytest.mark.parametrize("command", ["simulate", "record"])
@pytest.mark.parametrize("where", ["under_a_file", "proc"])
def test_an_out_directory_that_cannot_be_created_is_refused(
    command: str, where: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "plain").write_text("x")
    out = tmp_path / "plain" / "bag" if where == "under_a_file" else Path("/proc/bsp_edges_bag")
    argv = ["simulate", "--out", str(out)] if command == "simulate" else ["record", "/chatter", "--out", str(out)]
    code = main(argv)
    line = _one_error_line(capsys.readouterr().err, command)
    assert code == BAD_OPTION
    assert f"--out {out}" in line
    assert (tmp_path / "plain").read_text() == "x"


def test_simulate_still_refuses_an_existing_bag(bag: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["simulate", "--out", str(bag), "--duration", "5"])
    assert code == BAG_WRITE
    assert "refusing to overwrite" in _one_error_line(capsys.readouterr().err, "simulate")


def _result_file(bag: Path, tmp_path: Path) -> Path:
    result = tmp_path / "result.json"
    main(["identify", str(bag), "--json", str(result), "--format", "none"])
    assert result.exists()
    return result


@pytest.mark.parametrize("content", [b"x", b"", b"just some notes, not a database\n"])
def test_an_existing_file_that_is_not_a_store_is_refused_untouched(
    content: bytes, bag: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    result = _result_file(bag, tmp_path)
    capsys.readouterr()
    store = tmp_path / "store.sqlite"
    store.write_bytes(content)
    code = main(["sessions", "add", str(result), "--subject", "S01", "--store", str(store)])
    line = _one_error_line(capsys.readouterr().err, "sessions")
    assert code == STORE
    assert str(store) in line and "not a bsp_ros session store" in line
    assert store.read_bytes() == content
    assert not Path(f"{store}-wal").exists()


def test_a_new_store_file_is_still_created(bag: Path, tmp_path: Path) -> None:
    result = _result_file(bag, tmp_path)
    store = tmp_path / "new" / "store.sqlite"
    assert main(["sessions", "add", str(result), "--subject", "S01", "--store", str(store)]) == 0
    assert main(["sessions", "list", "--store", str(store)]) == 0  # the same recording twice is refused now
    assert store.read_bytes()[:16] == b"SQLite format 3\x00"


def test_deeply_nested_json_is_refused_with_a_message(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    deep = tmp_path / "deep.json"
    deep.write_text('{"segments": ' + "[" * 100_000 + "]" * 100_000 + "}")
    code = main(["sessions", "add", str(deep), "--subject", "S01", "--store", str(tmp_path / "s.sqlite")])
    line = _one_error_line(capsys.readouterr().err, "sessions")
    assert code == STORE
    assert str(deep) in line and "nested deeper" in line


@pytest.mark.parametrize(
    ("option", "value"), [("--duration", "-1"), ("--speed", "0"), ("--speed", "nan"), ("--speed", "1000")]
)
def test_demo_refuses_a_duration_or_speed_out_of_range(
    option: str, value: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as stop:
        main(["demo", option, value])
    line = _one_error_line(capsys.readouterr().err, "demo")
    assert stop.value.code == BAD_OPTION
    assert option in line and repr(value) in line


def test_a_valid_estimate_still_ends_in_the_json(bag: Path, tmp_path: Path) -> None:
    out = tmp_path / "new_dir" / "e.json"
    code = main(["identify", str(bag), "--json", str(out), "--format", "none"])
    assert code in (0, 1)
    assert json.loads(out.read_text())["schema"] == "bsp_ros/core/estimate/1"


@pytest.mark.parametrize("option", ["--out", "--csv", "--png"])
def test_report_outputs_are_checked_before_the_store_is_opened(
    option: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "plain").write_text("x")
    target = tmp_path / "plain" / "r"
    store = tmp_path / "s.sqlite"
    code = main(["report", "S01", option, str(target), "--store", str(store)])
    line = _one_error_line(capsys.readouterr().err, "report")
    assert code == BAD_OPTION  # an unknown subject in the (new) store would be 5
    assert f"{option} {target}" in line
    assert not store.exists()
