"""Fixed-width byte windows at many offsets of one buffer, gathered in bulk (message headers, floats, names)."""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view


def byte_windows(buf: np.ndarray, starts: np.ndarray, width: int) -> np.ndarray:
    """Bytes ``buf[s:s + width]`` for every start ``s``, as a C-contiguous (n, width) uint8 array.

    Rows of the buffer's sliding-window view, one index per row: an index per byte (``starts[:, None] + arange``)
    built an (n, width) int64 array first, 2-6 times slower (180,000 message headers: 13 -> 3.6 ms).

    Parameters
    ----------
    buf : (B,) uint8.
    starts : (n,) int64 offsets, each with ``width`` bytes after it in ``buf``.
    width : bytes per window.

    Raises
    ------
    IndexError
        A window runs past the buffer's end.
    """
    if width < 1 or width > buf.size:
        return buf[starts[:, None] + np.arange(width, dtype=np.int64)]
    return np.asarray(sliding_window_view(buf, width)[starts])
