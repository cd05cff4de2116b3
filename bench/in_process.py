"""`bsp` commands the trust benches run in process, their output swallowed: `bsp identify` and `bsp plan`.

Run from a clone with the worktree first on PYTHONPATH, as every bench is.
"""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path
from typing import Any

from bsp_ros.cli import main as bsp_main

# The therapist's ranges of the benches' planned rows: the shoulder at (0, 1.2) m, ranges in deg.
PLAN_RANGES = [
    "--shoulder", "0", "1.2", "--shoulder-range", "-70", "-10", "--elbow-range", "10", "100",
    "--wrist-range", "-20", "20",
]  # fmt: skip


def identify(bag: Path, out: Path, *extra: str) -> tuple[int, dict[str, Any]]:
    """``bsp identify BAG --json OUT [EXTRA...]``: the exit code and the estimate document, or {} where none was
    written."""
    sink = io.StringIO()
    with contextlib.redirect_stdout(sink), contextlib.redirect_stderr(sink):
        code = bsp_main(["identify", str(bag), "--json", str(out), "--format", "none", *extra])
    return code, (json.loads(out.read_text()) if out.exists() else {})


def planned_in_ranges(workdir: Path, duration_s: float) -> Path:
    """A ``bsp plan`` trajectory within :data:`PLAN_RANGES`, ``duration_s`` long, written once to
    ``workdir/plan.json``.

    Raises
    ------
    SystemExit
        `bsp plan` failed (its exit code named).
    """
    out = workdir / "plan.json"
    if not out.exists():
        argv = ["plan", *PLAN_RANGES, "--duration", f"{duration_s:g}", "--json", str(out)]
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            code = bsp_main(argv)
        if code != 0:
            raise SystemExit(f"bsp plan failed with exit code {code}")
    return out
