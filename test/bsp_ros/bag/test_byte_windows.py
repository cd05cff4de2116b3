"""Byte windows gathered in bulk: the same bytes as an index per byte, the buffer's end included."""

from __future__ import annotations

import numpy as np
import pytest

from bsp_ros.bag.byte_windows import byte_windows


def _per_byte(buf: np.ndarray, starts: np.ndarray, width: int) -> np.ndarray:
    return buf[starts[:, None] + np.arange(width, dtype=np.int64)]


@pytest.mark.parametrize("width", [1, 8, 16, 31, 48])
def test_windows_equal_an_index_per_byte(width: int) -> None:
    rng = np.random.default_rng(width)
    buf = rng.integers(0, 256, size=5000, dtype=np.uint8)
    starts = np.sort(rng.choice(buf.size - width + 1, size=400, replace=False)).astype(np.int64)
    starts[-1] = buf.size - width  # a window ending at the buffer's last byte
    got = byte_windows(buf, starts, width)
    assert got.flags["C_CONTIGUOUS"] and got.dtype == np.uint8
    np.testing.assert_array_equal(got, _per_byte(buf, starts, width))


def test_no_starts_give_no_rows() -> None:
    buf = np.arange(10, dtype=np.uint8)
    assert byte_windows(buf, np.zeros(0, dtype=np.int64), 4).shape == (0, 4)


@pytest.mark.parametrize("width", [4, 20])
def test_a_window_past_the_end_raises(width: int) -> None:
    buf = np.arange(10, dtype=np.uint8)
    with pytest.raises(IndexError):
        byte_windows(buf, np.array([8], dtype=np.int64), width)
