"""The output-path validators: accept what can be written, refuse with the path named, create nothing."""

from __future__ import annotations

from pathlib import Path

import pytest

from bsp_ros.errors import InputError
from bsp_ros.validation import check_output_dir, check_output_file


def _listing(root: Path) -> list[Path]:
    return sorted(root.rglob("*"))


def test_a_new_file_in_missing_directories_is_accepted_and_nothing_is_created(tmp_path: Path) -> None:
    target = tmp_path / "a" / "b" / "e.json"
    assert check_output_file("--json", target) == target
    assert _listing(tmp_path) == []


def test_an_existing_file_is_accepted_with_its_content_untouched(tmp_path: Path) -> None:
    target = tmp_path / "e.json"
    target.write_text("old\n")
    assert check_output_file("--json", str(target)) == target
    assert target.read_text() == "old\n"


def test_a_directory_is_not_a_file_name(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=f"--json {tmp_path} is a directory"):
        check_output_file("--json", tmp_path)


def test_a_file_under_a_regular_file_is_refused_naming_that_file(tmp_path: Path) -> None:
    (tmp_path / "plain").write_text("x")
    with pytest.raises(InputError, match=f"{tmp_path / 'plain'} is a file, not a directory"):
        check_output_file("--json", tmp_path / "plain" / "deeper" / "e.json")
    assert (tmp_path / "plain").read_text() == "x"


@pytest.mark.parametrize("target", ["/proc/bsp_validation.json", "/proc/version"])
def test_proc_is_refused(target: str) -> None:
    with pytest.raises(InputError, match=f"--json {target}"):
        check_output_file("--json", target)


def test_a_dangling_symlink_is_refused(tmp_path: Path) -> None:
    link = tmp_path / "link.json"
    link.symlink_to(tmp_path / "missing" / "target.json")
    with pytest.raises(InputError, match="dangling symbolic link"):
        check_output_file("--json", link)


def test_a_new_directory_is_accepted_and_not_created(tmp_path: Path) -> None:
    target = tmp_path / "x" / "bag"
    assert check_output_dir("--out", target) == target
    assert _listing(tmp_path) == []


def test_an_existing_directory_is_accepted_unchanged(tmp_path: Path) -> None:
    assert check_output_dir("--out", tmp_path) == tmp_path
    assert _listing(tmp_path) == []


def test_a_regular_file_is_not_a_directory(tmp_path: Path) -> None:
    (tmp_path / "plain").write_text("x")
    with pytest.raises(InputError, match="is a file, expected a directory"):
        check_output_dir("--out", tmp_path / "plain")


@pytest.mark.parametrize("where", ["under_a_file", "proc"])
def test_a_directory_that_cannot_be_created_is_refused(where: str, tmp_path: Path) -> None:
    (tmp_path / "plain").write_text("x")
    target = tmp_path / "plain" / "bag" if where == "under_a_file" else Path("/proc/bsp_validation_bag")
    with pytest.raises(InputError, match=f"--out {target}"):
        check_output_dir("--out", target)
