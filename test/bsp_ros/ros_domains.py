"""A ROS domain id of its own for every live test (rclpy + Fast DDS in separate processes)."""

from __future__ import annotations

import fcntl
import itertools
import os
import tempfile
from pathlib import Path
from typing import IO

#: Domain ids a machine commonly uses already (the default 0, tutorials' 1 and 42); the rest of 1..101
#: (Fast DDS's safe range on Linux: higher ids reach the ephemeral ports) is shared out.
AVOID = frozenset({0, 1, 42})
FREE = tuple(d for d in range(1, 102) if d not in AVOID)
#: Test runs at once on one machine (two suites, a suite and `colcon test`) that never share a domain: each
#: takes every PARTITIONS-th id, so one run still reuses an id only after ~49 others (a killed node's
#: participant lingers in discovery for its lease, 20 s by default).
PARTITIONS = 2
_counter = itertools.count()
_ids: tuple[int, ...] | None = None
_lock: IO[str] | None = None  # held for the process's life: the claim on its partition


def _claim_partition() -> tuple[int, ...]:
    """The domain ids of the first partition no other process holds (a lock file), or all of them if each is
    held (the runs beyond PARTITIONS then share ids, spread by their pids)."""
    global _lock
    directory = Path(tempfile.gettempdir()) / "bsp_ros_test_domains"
    directory.mkdir(exist_ok=True)
    for k in range(PARTITIONS):
        handle = (directory / f"partition_{k}.lock").open("a")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            continue
        _lock = handle
        return FREE[k::PARTITIONS]
    return FREE


def next_domain_id() -> int:
    """A domain id unique within this test process (a counter) and apart from other test runs' (a partition of
    the ids per run), its start spread by the pid."""
    global _ids
    if _ids is None:
        _ids = _claim_partition()
    return _ids[(os.getpid() * 7 + next(_counter)) % len(_ids)]
