"""Passive-moment curves of a session: kept as measured, and sampled at fixed angles so sessions compare."""

from __future__ import annotations

import math
import re
from typing import Any

from bsp_ros.clinic.store.records import ParamKey, Quantity
from bsp_ros.core.estimate_schema import Source
from bsp_ros.core.quantities import PASSIVE_CURVE
from bsp_ros.errors import StoreError

CURVE_KEY = PASSIVE_CURVE
"""``joints.<joint>.passive_curve`` = ``{"angle_deg": [...], "moment_nm": [...], "std_nm": [...]}``."""
STEP_DEG = 5
"""Curves are compared at the multiples of this angle inside the measured range (no extrapolation)."""
MAX_POINTS = 2000
_ANGLE_KEY = re.compile(r"passive_moment_at_(-?\d+)deg_nm")


def angle_key(angle_deg: int) -> str:
    """The quantity key of the passive moment at ``angle_deg``: ``passive_moment_at_30deg_nm``."""
    return f"passive_moment_at_{angle_deg}deg_nm"


def angle_of(quantity: str) -> int | None:
    """The angle (deg) of a fixed-angle passive-moment key, None for other quantities."""
    found = _ANGLE_KEY.fullmatch(quantity)
    return int(found.group(1)) if found else None


def _numbers(value: Any, name: str) -> list[float]:
    if not isinstance(value, list) or len(value) > MAX_POINTS:
        raise StoreError(f"{name} must be a list of at most {MAX_POINTS} numbers")
    out = []
    for item in value:
        if isinstance(item, bool) or not isinstance(item, int | float):
            raise StoreError(f"{name} must hold numbers, got {item!r:.40}")
        out.append(float(item))
    return out


def check_curve(joint: str, block: Any) -> dict[str, list[float]]:
    """A passive curve checked: equal-length finite lists, angles strictly increasing (sorted here)."""
    where = f"joints.{joint}.{CURVE_KEY}"
    if not isinstance(block, dict):
        raise StoreError(f"{where} must be an object with angle_deg, moment_nm and std_nm")
    angle = _numbers(block.get("angle_deg"), f"{where}.angle_deg")
    moment = _numbers(block.get("moment_nm"), f"{where}.moment_nm")
    std = _numbers(block.get("std_nm", [0.0] * len(angle)), f"{where}.std_nm")
    if not len(angle) == len(moment) == len(std):
        raise StoreError(f"{where}: angle_deg, moment_nm and std_nm differ in length")
    rows = sorted((a, m, s) for a, m, s in zip(angle, moment, std, strict=True) if math.isfinite(a + m + s))
    if len({a for a, _, _ in rows}) != len(rows):
        raise StoreError(f"{where}.angle_deg repeats an angle")
    return {
        "angle_deg": [a for a, _, _ in rows],
        "moment_nm": [m for _, m, _ in rows],
        "std_nm": [abs(s) for _, _, s in rows],
    }


def sample_curve(curve: dict[str, list[float]], step_deg: int = STEP_DEG) -> dict[int, tuple[float, float]]:
    """The curve's moment and std (linear interpolation) at the multiples of ``step_deg`` it covers."""
    angles = curve["angle_deg"]
    if len(angles) < 2:
        return {}
    found = {}
    first = math.ceil(angles[0] / step_deg) * step_deg
    for target in range(first, math.floor(angles[-1]) + 1, step_deg):
        k = next(i for i in range(1, len(angles)) if angles[i] >= target)
        a0, a1 = angles[k - 1], angles[k]
        w = (target - a0) / (a1 - a0)
        moment = curve["moment_nm"][k - 1] * (1 - w) + curve["moment_nm"][k] * w
        std = curve["std_nm"][k - 1] * (1 - w) + curve["std_nm"][k] * w
        found[target] = (moment, std)
    return found


def passive_curves(joints: Any) -> tuple[dict[str, Any], dict[ParamKey, Quantity]]:
    """Curves of an estimate's ``joints`` block, and their moments at fixed angles as quantities.

    Returns
    -------
    curves, parameters
        ``joint -> curve`` (checked) and ``("joints", joint, "passive_moment_at_<a>deg_nm") -> Quantity``;
        both empty when the estimate has no curve.
    """
    curves: dict[str, Any] = {}
    parameters: dict[ParamKey, Quantity] = {}
    if not isinstance(joints, dict):
        return curves, parameters
    for joint, block in joints.items():
        if isinstance(block, dict) and CURVE_KEY in block:
            curve = check_curve(str(joint), block[CURVE_KEY])
            curves[str(joint)] = curve
            for angle, (moment, std) in sample_curve(curve).items():
                parameters[("joints", str(joint), angle_key(angle))] = Quantity(
                    value=moment, std=std, source=Source.DATA
                )
    return curves, parameters
