"""A ROS domain id of its own for every live test (rclpy + Fast DDS in separate processes)."""

from __future__ import annotations

import itertools
import os

#: Domain ids a machine commonly uses already (the default 0, tutorials' 1 and 42); the rest of 1..101
#: (Fast DDS's safe range on Linux: higher ids reach the ephemeral ports) is shared out.
AVOID = frozenset({0, 1, 42})
FREE = tuple(d for d in range(1, 102) if d not in AVOID)
_counter = itertools.count()


def next_domain_id() -> int:
    """A domain id unique within this test process (a counter), spread between processes by the pid."""
    return FREE[(os.getpid() * 7 + next(_counter)) % len(FREE)]
