"""Constants and value checks shared by the simulator's specs (plausibility bounds, tuples of floats, rotations)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_scalar, check_positive

GRAVITY_M_S2 = 9.81
TRUTH_SCHEMA = "bsp_ros/truth/1"
# 2023-11-14T22:13:20Z: a realistic ROS time (a stamp of 0 is an error on the wire).
DEFAULT_START_NS = 1_700_000_000_000_000_000

# Plausibility bounds of a spec (anything outside is a typo, not a subject).
MAX_LENGTH_M = 1.0
MIN_LENGTH_M = 0.01
MAX_MASS_KG = 30.0
MAX_COM_FRACTION = 1.5  # COM up to 1.5 segment lengths from the proximal joint (hand past the contact point)
MAX_INERTIA_KGM2 = 5.0  # about the COM; a whole arm about the shoulder is ~0.5 kg m^2
MAX_COULOMB_NM = 20.0
MAX_VISCOUS_NMS = 100.0
MAX_STIFFNESS_NM_PER_RAD = 100.0
MAX_OFFSET_NM = 20.0
MAX_DURATION_S = 86_400.0
MIN_ELBOW_SIN = math.sin(math.radians(5.0))  # keep the elbow 5 deg away from a straight/folded arm
JITTER_CLIP_PERIODS = 0.4  # |jitter| <= 0.4 period keeps stamps strictly increasing


def float_tuple(
    name: str,
    values: Any,
    n: int | None = None,
    lo: float = -math.inf,
    hi: float = math.inf,
    positive: bool = False,
) -> tuple[float, ...]:
    """Return ``values`` as a tuple of floats, each finite and in range; raise InputError naming the value."""
    if isinstance(values, str | bytes) or not isinstance(values, Sequence | np.ndarray):
        raise InputError(f"{name} must be a sequence of numbers, got {values!r}")
    items = list(values)
    if n is not None and len(items) != n:
        raise InputError(f"{name} must have {n} entries, got {len(items)}: {tuple(values)!r}")
    out: list[float] = []
    for i, item in enumerate(items):
        label = f"{name}[{i}]"
        out.append(check_positive(label, item, hi) if positive else check_finite_scalar(label, item, lo, hi))
    return tuple(out)


def check_int(name: str, value: Any, lo: int, hi: int | None = None) -> int:
    """Return ``value`` as an int if it is an integer (not bool) within ``[lo, hi]``."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise InputError(f"{name} must be an integer, got {value!r}")
    number = int(value)
    if number < lo or (hi is not None and number > hi):
        raise InputError(f"{name} must be within [{lo}, {hi if hi is not None else 'inf'}], got {value!r}")
    return number


def check_bool(name: str, value: Any) -> bool:
    """Return ``value`` if it is True or False (not 0/1 or a string)."""
    if not isinstance(value, bool):
        raise InputError(f"{name} must be True or False, got {value!r}")
    return value


def check_n_segments(n_segments: Any, what: str = "n_segments") -> int:
    """Return the number of segments if it is 2 or 3."""
    if isinstance(n_segments, bool) or n_segments not in (2, 3):
        raise InputError(f"{what} must be 2 or 3, got {n_segments!r}")
    return int(n_segments)


def rotation_from_rpy_deg(roll_deg: float, pitch_deg: float, yaw_deg: float) -> np.ndarray:
    """Rotation matrix of fixed-axis roll, pitch, yaw (ROS/tf2 ``setRPY`` convention).

    Parameters
    ----------
    roll_deg, pitch_deg, yaw_deg : float
        Rotations about the fixed x, then y, then z axes, in degrees.

    Returns
    -------
    (3, 3) float64 ndarray
        ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``.
    """
    r, p, y = (
        math.radians(check_finite_scalar(n, v))
        for n, v in zip(("roll", "pitch", "yaw"), (roll_deg, pitch_deg, yaw_deg), strict=True)
    )
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return rz @ ry @ rx


def rotations_about_x(angle_rad: npt.ArrayLike) -> np.ndarray:
    """Rotations about the x axis by ``angle_rad`` (+y toward +z): (N,) rad -> (N, 3, 3)."""
    angle = np.atleast_1d(np.asarray(angle_rad, dtype=np.float64))
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros((angle.size, 3, 3))
    out[:, 0, 0] = 1.0
    out[:, 1, 1], out[:, 1, 2] = c, -s
    out[:, 2, 1], out[:, 2, 2] = s, c
    return out
