"""A time-stamped sample buffer that drops what is older than a horizon: fixed memory for endless streams."""

from __future__ import annotations

import numpy as np


class TimedBuffer:
    """Rows of ``width`` floats with int64 stamps, strictly increasing, kept for ``horizon_ns``.

    Appending is O(1) amortised; memory is bounded by the horizon times the rate.
    """

    def __init__(self, width: int, horizon_ns: int, capacity: int = 4096) -> None:
        self.width = width
        self.horizon_ns = horizon_ns
        self._t = np.zeros(capacity, dtype=np.int64)
        self._v = np.zeros((capacity, width))
        self._start = 0
        self._stop = 0

    def __len__(self) -> int:
        return self._stop - self._start

    @property
    def last_t_ns(self) -> int | None:
        """Stamp of the newest row, None when empty."""
        return int(self._t[self._stop - 1]) if len(self) else None

    def clear(self) -> None:
        """Forget every row."""
        self._start = self._stop = 0

    def append(self, t_ns: int, values: np.ndarray) -> None:
        """Add a row (the caller guarantees a stamp after the last) and drop rows beyond the horizon."""
        if self._stop == self._t.size:
            self._compact(t_ns)
        self._t[self._stop] = t_ns
        self._v[self._stop] = values
        self._stop += 1

    def _compact(self, now_ns: int) -> None:
        keep_from = self._start + int(np.searchsorted(self._t[self._start : self._stop], now_ns - self.horizon_ns))
        count = self._stop - keep_from
        if count > self._t.size // 2:  # still crowded: grow
            self._t = np.concatenate((self._t, np.zeros_like(self._t)))
            self._v = np.concatenate((self._v, np.zeros_like(self._v)))
        self._t[:count] = self._t[keep_from : self._stop]
        self._v[:count] = self._v[keep_from : self._stop]
        self._start, self._stop = 0, count

    def since(self, t_ns: int) -> tuple[np.ndarray, np.ndarray]:
        """Copies of the stamps (K,) and rows (K, width) at or after ``t_ns``."""
        first = self._start + int(np.searchsorted(self._t[self._start : self._stop], t_ns))
        return self._t[first : self._stop].copy(), self._v[first : self._stop].copy()
