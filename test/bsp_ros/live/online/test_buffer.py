"""The timed buffer keeps a fixed horizon: bounded memory for an endless stream."""

from __future__ import annotations

import numpy as np

from bsp_ros.live.online.buffer import TimedBuffer


def test_memory_stays_bounded_over_an_endless_stream() -> None:
    buffer = TimedBuffer(3, horizon_ns=5_000_000_000, capacity=1024)
    for k in range(100_000):  # 100 s at 1 kHz
        buffer.append(1_000_000_000 + k * 1_000_000, np.full(3, float(k)))
    assert buffer._t.size <= 4 * 5_000 * 2  # never grows beyond a few horizons
    t_ns, rows = buffer.since(buffer.last_t_ns - 4_000_000_000)
    assert t_ns.size == 4001
    np.testing.assert_array_equal(rows[:, 0], np.arange(100_000 - 4001, 100_000))


def test_since_returns_copies_in_order() -> None:
    buffer = TimedBuffer(1, horizon_ns=10)
    for t in (1, 2, 3):
        buffer.append(t, np.array([t * 10.0]))
    t_ns, rows = buffer.since(2)
    rows[:] = 0
    np.testing.assert_array_equal(t_ns, [2, 3])
    np.testing.assert_array_equal(buffer.since(0)[1][:, 0], [10.0, 20.0, 30.0])
