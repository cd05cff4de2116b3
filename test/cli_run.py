"""Running `bsp` in-process from a test: its exit code, stdout and stderr."""

from __future__ import annotations

import pytest

from bsp_ros.cli import main


def bsp(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    """``bsp ARGV...`` through ``bsp_ros.cli.main``: (exit code, what it printed on stdout, on stderr)."""
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err
