"""The README's "Exit codes" table lists every exit code `bsp` can return, and no other."""

from __future__ import annotations

import re
from pathlib import Path

from bsp_ros import errors
from bsp_ros.cli import EXIT_BROKEN_PIPE, EXIT_INTERRUPTED, identify

README = Path(__file__).resolve().parents[3] / "README.md"


def _documented_codes() -> set[int]:
    section = README.read_text(encoding="utf-8").split("## Exit codes", 1)[1].split("\n## ", 1)[0]
    return {int(code) for code in re.findall(r"^\| (\d+) \|", section, flags=re.MULTILINE)}


def _error_classes(cls: type[errors.BspError]) -> list[type[errors.BspError]]:
    return [cls] + [sub for child in cls.__subclasses__() for sub in _error_classes(child)]


def test_the_readme_table_covers_every_exit_code() -> None:
    raised = {cls.exit_code for cls in _error_classes(errors.BspError)}
    # 0 success, 1 invalid estimate / damaged bag played / demo not near the truth, 130 Ctrl-C and 141 a reader
    # that went away (cli.main).
    returned = {0, identify.EXIT_INVALID, EXIT_INTERRUPTED, EXIT_BROKEN_PIPE, *identify.BAG_EXIT_CODES.values()}
    assert _documented_codes() == raised | returned
