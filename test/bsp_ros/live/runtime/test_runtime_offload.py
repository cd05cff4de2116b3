"""The worker process: results, errors, restart after a crash, and exit when its parent is killed."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from bsp_ros.errors import RuntimeBackendError
from bsp_ros.live.runtime.offload import ProcessOffload


def test_runs_in_another_process_and_reraises_errors() -> None:
    offload = ProcessOffload()
    try:
        assert offload.run(os.getpid) != os.getpid()
        with pytest.raises(ZeroDivisionError):
            offload.run(divmod, 1, 0)
    finally:
        offload.close()


def test_a_dead_child_is_reported_and_replaced() -> None:
    offload = ProcessOffload()
    try:
        first = offload.run(os.getpid)
        with pytest.raises(RuntimeBackendError, match="died"):
            offload.run(os.kill, first, signal.SIGKILL)
        assert offload.run(os.getpid) not in (first, os.getpid()) and offload.restarts == 1
    finally:
        offload.close()


def _running(pid: int) -> bool:
    """True while ``pid`` exists and has not exited (an exited orphan may wait as a zombie to be reaped)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def test_the_child_exits_when_its_parent_is_killed() -> None:
    script = textwrap.dedent(
        """
        import os, sys, time
        from bsp_ros.live.runtime.offload import ProcessOffload
        if __name__ == "__main__":
            offload = ProcessOffload()
            print(offload.run(os.getpid), flush=True)
            time.sleep(60)
        """
    )
    parent = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    assert parent.stdout is not None
    child = int(parent.stdout.readline())
    parent.send_signal(signal.SIGKILL)
    parent.wait(10)
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        if not _running(child):
            return
        time.sleep(0.1)
    os.kill(child, signal.SIGKILL)
    pytest.fail(f"the worker process {child} outlived its killed parent")
