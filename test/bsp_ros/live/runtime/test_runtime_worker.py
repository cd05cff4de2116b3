"""The latest-job worker: order, replacement of waiting jobs, and survival of a failing job."""

from __future__ import annotations

import threading

from bsp_ros.live.runtime.worker import LatestJobWorker


def test_a_waiting_job_is_replaced_by_a_newer_one_and_jobs_run_in_order() -> None:
    release = threading.Event()
    done: list[int] = []
    worker = LatestJobWorker("test-worker")
    worker.submit(lambda: (release.wait(5.0), done.append(0)))  # type: ignore[func-returns-value]
    assert not worker.wait_idle(0.05)  # job 0 is running
    for k in (1, 2, 3):
        worker.submit(lambda k=k: done.append(k))
    release.set()
    assert worker.wait_idle(5.0)
    worker.close()
    assert done == [0, 3] and worker.dropped == 2


def test_a_failing_job_is_reported_and_the_next_one_runs() -> None:
    errors: list[BaseException] = []
    done: list[str] = []
    worker = LatestJobWorker("test-worker", on_error=errors.append)
    worker.submit(lambda: [][1])  # type: ignore[func-returns-value]
    assert worker.wait_idle(5.0)
    worker.submit(lambda: done.append("next"))
    assert worker.wait_idle(5.0)
    worker.close()
    assert [type(e) for e in errors] == [IndexError] and done == ["next"]
