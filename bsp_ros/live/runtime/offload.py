"""Run CPU-heavy functions in one child process, so that a node's callbacks keep the GIL to themselves."""

from __future__ import annotations

import multiprocessing
import os
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from bsp_ros.errors import RuntimeBackendError


def _child_init(parent_pid: int, initializer: Callable[..., None] | None, initargs: tuple[Any, ...]) -> None:
    """In the child: exit when the parent is gone (a node killed by a signal runs no clean-up), then set up."""

    def watch_parent() -> None:
        while os.getppid() == parent_pid:
            time.sleep(0.5)
        os._exit(0)

    threading.Thread(target=watch_parent, name="bsp_ros-offload-parent-watch", daemon=True).start()
    if initializer is not None:
        initializer(*initargs)


class ProcessOffload:
    """A single spawned worker process (``spawn``: forking a process that runs DDS threads is unsafe).

    Python threads share one interpreter lock: a 100 ms estimate on a thread delays a 1 kHz callback thread
    by a switch interval per sample and competes with it for one core. In a child process it uses another.

    Parameters
    ----------
    initializer : module-level function run once in the child (sets up its state), or None.
    initargs : its arguments (picklable).
    """

    def __init__(self, initializer: Callable[..., None] | None = None, initargs: Sequence[Any] = ()) -> None:
        self._initializer = initializer
        self._initargs = tuple(initargs)
        self._pool = self._start()
        self.restarts = 0

    def _start(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(
            max_workers=1,
            mp_context=multiprocessing.get_context("spawn"),
            initializer=_child_init,
            initargs=(os.getpid(), self._initializer, self._initargs),
        )

    def run(self, fn: Callable[..., Any], *args: Any) -> Any:
        """Call module-level ``fn(*args)`` in the child and return its result (exceptions are re-raised).

        Raises
        ------
        RuntimeBackendError
            If the child died (it is restarted for the next call).
        """
        try:
            return self._pool.submit(fn, *args).result()
        except BrokenProcessPool as exc:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._start()
            self.restarts += 1
            raise RuntimeBackendError(f"the worker process died and was restarted: {exc}") from exc

    def close(self) -> None:
        """Stop the child."""
        self._pool.shutdown(wait=True, cancel_futures=True)
