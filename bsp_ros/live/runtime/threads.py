"""A node's BLAS: one thread, since the cell's nodes share the machine's cores."""

from __future__ import annotations

import os

__all__ = ["BLAS_THREAD_ENV", "single_threaded_blas"]

# Any of these set by the user (or a launch file) is their choice of BLAS threads, kept as it is.
BLAS_THREAD_ENV = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")


def single_threaded_blas() -> bool:
    """Limit the BLAS libraries loaded so far (numpy's, scipy's) to one thread; True if limited.

    A node's products are small (a 30 s window, a few columns): OpenBLAS's second thread on a 2-core cell takes
    no time off them and, waiting busily for work, takes CPU from the simulator and the other nodes (the
    identifier's threads other than its executor's). The windowed update's mean is the same either way and its
    worst case lower with one thread (bench/README.md, live latency).
    Call after the node's modules are imported (a library loaded later keeps its default). Without threadpoolctl
    (pip installs it with bsp_ros; rosdep has no key for it) BLAS keeps its default.
    """
    if any(os.environ.get(name) for name in BLAS_THREAD_ENV):
        return False
    try:  # here: only a node's process needs it; a cell from apt may lack it (rosdep has no key for it)
        from threadpoolctl import threadpool_limits
    except ImportError:
        return False

    threadpool_limits(limits=1, user_api="blas")
    return True
