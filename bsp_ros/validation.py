"""`check_*` validators: accept a value only if finite and in range, and return it."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.errors import InputError


def check_finite_scalar(name: str, value: Any, lo: float = -math.inf, hi: float = math.inf) -> float:
    """Return ``value`` as a float if it is finite and ``lo <= value <= hi``; raise InputError naming it."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    # `not (lo <= x <= hi)` also rejects NaN, which slips through `x > hi` guards.
    if not math.isfinite(number) or not (lo <= number <= hi):
        raise InputError(f"{name} must be finite and within [{lo:g}, {hi:g}], got {value!r}")
    return number


def check_positive(name: str, value: Any, hi: float = math.inf) -> float:
    """Return ``value`` as a float if it is finite, strictly positive and at most ``hi``."""
    number = check_finite_scalar(name, value, 0.0, hi)
    if number <= 0.0:
        raise InputError(f"{name} must be positive, got {value!r}")
    return number


def check_finite_array(name: str, array: npt.ArrayLike, shape: tuple[int | None, ...] | None = None) -> np.ndarray:
    """Return ``array`` as a float64 ndarray if all its entries are finite and its shape matches.

    ``None`` in ``shape`` accepts any length along that axis.
    """
    values = np.asarray(array, dtype=np.float64)
    if shape is not None:
        if values.ndim != len(shape) or any(
            want is not None and got != want for got, want in zip(values.shape, shape, strict=True)
        ):
            raise InputError(f"{name} must have shape {shape}, got {values.shape}")
    bad = ~np.isfinite(values)
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise InputError(f"{name} has {int(bad.sum())} non-finite values (first at {index}: {values[index]})")
    return values


def check_stamps_ns(name: str, t_ns: npt.ArrayLike) -> np.ndarray:
    """Return ``t_ns`` as int64 if strictly increasing and positive (ROS time 0 is an error)."""
    stamps = np.asarray(t_ns)
    if stamps.ndim != 1:
        raise InputError(f"{name} must be one-dimensional, got shape {stamps.shape}")
    if stamps.size and not np.issubdtype(stamps.dtype, np.integer):
        raise InputError(f"{name} must be integer nanoseconds, got dtype {stamps.dtype}")
    stamps = stamps.astype(np.int64)
    if stamps.size and stamps[0] <= 0:
        raise InputError(f"{name} starts at {int(stamps[0])} ns: a stamp of 0 or less is not a time")
    steps = np.diff(stamps)
    if (steps <= 0).any():
        first = int(np.argmax(steps <= 0))
        raise InputError(
            f"{name} is not strictly increasing: stamp {first + 1} ({int(stamps[first + 1])} ns) "
            f"follows {int(stamps[first])} ns"
        )
    return stamps
