"""single_threaded_blas: numpy's and scipy's BLAS at one thread in a node's process, unless the user chose."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from bsp_ros.live.runtime.threads import BLAS_THREAD_ENV

# In a fresh process (the limit stays for the process): each loaded BLAS library's threads before and after the call.
SCRIPT = """
import json
import numpy, scipy.linalg.lapack
from threadpoolctl import threadpool_info
from bsp_ros.live.runtime.threads import single_threaded_blas
def threads():
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
before = threads()
limited = single_threaded_blas()
print(json.dumps([limited, before, threads()]))
"""


def _run(**env: str) -> tuple[bool, list[int], list[int]]:
    clean = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_ENV}
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], env={**clean, **env}, capture_output=True, text=True, timeout=60, check=True
    )
    limited, before, after = json.loads(done.stdout)
    return bool(limited), before, after


def test_every_loaded_blas_is_limited_to_one_thread() -> None:
    limited, before, after = _run()
    assert limited
    assert len(before) >= 1  # numpy's OpenBLAS at least (scipy's own too, where its wheel bundles one)
    if (os.cpu_count() or 1) > 1:
        assert max(before) > 1  # OpenBLAS starts a thread per core: the call is what brings it to one
    assert after == [1] * len(before)


def test_the_users_choice_of_threads_is_kept() -> None:
    limited, before, after = _run(OPENBLAS_NUM_THREADS="2")
    assert not limited
    assert after == before
