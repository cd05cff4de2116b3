"""single_threaded_blas: numpy's and scipy's BLAS at one thread in a node's process, unless the user chose."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from bsp_ros.live.runtime.threads import BLAS_THREAD_ENV

# In a fresh process (the limit stays for the process): the BLAS threads after the call, per library.
SCRIPT = """
import json
import numpy, scipy.linalg.lapack
from threadpoolctl import threadpool_info
from bsp_ros.live.runtime.threads import single_threaded_blas
limited = single_threaded_blas()
print(json.dumps([limited, sorted(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")]))
"""


def _run(**env: str) -> tuple[bool, list[int]]:
    clean = {k: v for k, v in os.environ.items() if k not in BLAS_THREAD_ENV}
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], env={**clean, **env}, capture_output=True, text=True, timeout=60, check=True
    )
    limited, threads = json.loads(done.stdout)
    return bool(limited), threads


def test_every_loaded_blas_is_limited_to_one_thread() -> None:
    limited, threads = _run()
    assert limited
    assert threads and threads == [1] * len(threads)  # numpy's and scipy's OpenBLAS alike


def test_the_users_choice_of_threads_is_kept() -> None:
    limited, threads = _run(OPENBLAS_NUM_THREADS="2")
    assert not limited
    assert threads and threads == [2] * len(threads)
