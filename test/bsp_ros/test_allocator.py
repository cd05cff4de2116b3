"""reuse_freed_memory: a freed 2 MB array's pages serve the next one without new page faults."""

from __future__ import annotations

import subprocess
import sys

import pytest

# In a fresh process: the faults of three 2 MB arrays made and freed in turn, after reuse_freed_memory or not.
_SCRIPT = """
import resource, sys
import numpy as np
from bsp_ros.allocator import reuse_freed_memory
print(reuse_freed_memory() if sys.argv[1] == "1" else False)
for _ in range(3):
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    array = np.ones(1 << 18)
    del array
    print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def _faults(reuse: bool) -> tuple[bool, list[int]]:
    out = subprocess.run(
        [sys.executable, "-c", _SCRIPT, "1" if reuse else "0"], capture_output=True, text=True, check=True
    ).stdout.split()
    return out[0] == "True", [int(v) for v in out[1:]]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_freed_array_is_reused_without_page_faults() -> None:
    was_set, faults = _faults(True)
    assert was_set
    # 2 MB is 512 pages: the first array faults them in, the next reuses them.
    assert faults[0] > 400
    assert faults[1] < 50 and faults[2] < 50


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_default_allocator_faults_the_second_array_again() -> None:
    # What the setting changes: by default the first block is mapped and unmapped, the second faulted in afresh.
    _, faults = _faults(False)
    assert faults[1] > 400
