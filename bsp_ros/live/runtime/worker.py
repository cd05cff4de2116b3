"""One background thread that runs the newest submitted job: slow estimates off the callback thread."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

Job = Callable[[], None]


class LatestJobWorker:
    """Runs submitted jobs one at a time, in order, on a daemon thread; a job still waiting when a newer
    one arrives is dropped (an estimate nobody will read is not worth computing).

    The node's executor thread stays free for the sensor callbacks while an estimate is computed: a
    1 kHz wrench is then delayed by at most a GIL switch interval, not by a whole estimate.

    Parameters
    ----------
    name : thread name (shows in ``py-spy`` and ``top -H``).
    on_error : called with the exception when a job raises; the worker carries on with the next job.
    """

    def __init__(self, name: str, on_error: Callable[[BaseException], None] | None = None) -> None:
        self._condition = threading.Condition()
        self._pending: Job | None = None
        self._busy = False
        self._closed = False
        self.dropped = 0
        self._on_error = on_error or (lambda exc: logging.getLogger("bsp_ros").exception("%s failed", name))
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def submit(self, job: Job) -> None:
        """Queue ``job``, replacing one that has not started yet."""
        with self._condition:
            if self._closed:
                return
            if self._pending is not None:
                self.dropped += 1
            self._pending = job
            self._condition.notify()

    def wait_idle(self, timeout_s: float) -> bool:
        """Block until no job is pending or running; False on timeout."""
        with self._condition:
            return self._condition.wait_for(lambda: self._pending is None and not self._busy, timeout_s)

    def close(self, timeout_s: float = 5.0) -> None:
        """Finish the running job, drop a pending one, and stop the thread."""
        with self._condition:
            self._closed = True
            self._pending = None
            self._condition.notify_all()
        self._thread.join(timeout_s)

    def _run(self) -> None:
        while True:
            with self._condition:
                self._condition.wait_for(lambda: self._pending is not None or self._closed)
                if self._closed:
                    return
                job, self._pending, self._busy = self._pending, None, True
            try:
                assert job is not None
                job()
            except Exception as exc:
                self._on_error(exc)
            finally:
                with self._condition:
                    self._busy = False
                    self._condition.notify_all()
