"""`check_*` validators: accept a value only if finite and in range (or a path only if writable), and return it."""

from __future__ import annotations

import math
import os
import stat
import tempfile
from pathlib import Path
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
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number, got {value!r}") from None
    # One message with the whole allowed range, whichever side the value fell off (0 itself is outside).
    if not (math.isfinite(number) and 0.0 < number <= hi):
        allowed = "greater than 0" if math.isinf(hi) else f"within (0, {hi:g}]"
        raise InputError(f"{name} must be finite and {allowed}, got {value!r}")
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


def _nearest_existing(path: Path) -> Path:
    """``path`` or its closest ancestor that exists (``.`` for a relative path with no existing part)."""
    for candidate in (path, *path.parents):
        if os.path.lexists(candidate):
            return candidate
    return Path(".")


def _check_creatable_under(name: str, path: Path) -> None:
    """Raise InputError unless ``path`` (not existing yet) can be created: every existing ancestor on the way
    is a directory that accepts a new file. Probed by creating an anonymous file there, since permission bits
    say nothing when running as root, on /proc or on a read-only mount."""
    ancestor = _nearest_existing(path.parent)
    if not ancestor.is_dir():
        raise InputError(f"{name} {path}: {ancestor} is a file, not a directory")
    try:
        tempfile.TemporaryFile(dir=ancestor).close()
    except OSError as error:
        raise InputError(f"{name} {path}: cannot create files in {ancestor} ({error.strerror})") from None


def check_output_file(name: str, path: str | os.PathLike[str]) -> Path:
    """Return ``path`` as a Path if a file can be written there; raise InputError naming it otherwise.

    Checked before any slow work, so a result is never computed only to be lost: ``path`` must not be a
    directory, an existing regular file must be writable, and a new one creatable (missing parent directories
    are fine if they can be created). Existing devices and pipes (``/dev/stdout``) are accepted as they are.
    Nothing is created or changed.
    """
    target = Path(path).expanduser()
    if target.is_dir():
        raise InputError(f"{name} {target} is a directory, expected a file name")
    if not os.path.lexists(target):
        _check_creatable_under(name, target)
        return target
    if not target.exists():
        raise InputError(f"{name} {target} is a dangling symbolic link")
    if stat.S_ISREG(target.stat().st_mode):
        try:
            with open(target, "ab"):  # append mode: opens for writing without touching the content
                pass
        except OSError as error:
            raise InputError(f"{name} {target}: cannot write this file ({error.strerror})") from None
    return target


def check_output_dir(name: str, path: str | os.PathLike[str]) -> Path:
    """Return ``path`` as a Path if a directory can be written there; raise InputError naming it otherwise.

    An existing ``path`` must be a directory that accepts new files; a new one must be creatable (its nearest
    existing ancestor a directory that accepts new entries). Whether an existing directory may be written into
    is the writer's decision (the bag writers refuse it). Nothing is created.
    """
    target = Path(path).expanduser()
    if os.path.lexists(target) and not target.is_dir():
        raise InputError(f"{name} {target} is a file, expected a directory")
    if target.is_dir():
        try:
            tempfile.TemporaryFile(dir=target).close()
        except OSError as error:
            raise InputError(f"{name} {target}: cannot create files in it ({error.strerror})") from None
        return target
    _check_creatable_under(name, target)
    return target
