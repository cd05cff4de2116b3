"""The process's memory allocator: glibc's malloc set to reuse the large arrays an identification frees."""

from __future__ import annotations

import sys

# glibc's mallopt(3) parameters (malloc.h).
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
# Blocks up to this size come from the heap and are reused when freed: glibc's largest allowed threshold on
# 64-bit. By default blocks over 128 kB (rising to the largest freed so far) are mapped afresh and unmapped
# when freed, so every temporary array of a fit pays its page faults again: a 10-minute session's arrays are
# 0.5-1.5 MB per column, tens of them per step.
MMAP_THRESHOLD_BYTES = 32 * 1024 * 1024
# Free memory at the heap's top is returned to the system only above this: a step's temporaries are reused by
# the next step instead of being returned and faulted in again.
TRIM_THRESHOLD_BYTES = 512 * 1024 * 1024


def reuse_freed_memory() -> bool:
    """Set glibc's malloc to keep and reuse freed blocks up to :data:`MMAP_THRESHOLD_BYTES`; True if it was set.

    An identification allocates and frees the same large arrays over and over; kept, they are not faulted in anew
    each time (the figures: bench/README.md, ``identify_vs_anyreader``). Elsewhere than glibc on Linux nothing is
    changed.
    """
    if not sys.platform.startswith("linux"):
        return False
    import ctypes  # here, not at import: `bsp --version` and `--help` never call this (numpy imports it anyway)

    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):  # not glibc (musl has no mallopt)
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    # Both are needed: a trim threshold alone also fixes the mmap threshold at its 128 kB default (mallopt(3)).
    return bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES)) and bool(
        mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES)
    )
