"""A live estimate as terminal lines, shared by `bsp demo` (beside the simulated truth) and `bsp watch` (any cell).

Light at import (the standard library only): the `bsp` parser imports every subcommand module at start.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from typing import Any

__all__ = ["ROW_KEYS", "estimate_rows", "quantity_cells", "state_line", "support_line"]

#: The quantities a live table shows: each segment's static moment (what gravity pulls through, what a robot
#: carries) and each joint's Coulomb friction (the passive moment that resists motion).
ROW_KEYS: tuple[tuple[str, str], ...] = (("segments", "static_moment_kgm"), ("joints", "coulomb_nm"))


def estimate_rows(
    document: Mapping[str, Any], keys: Sequence[tuple[str, str]] = ROW_KEYS
) -> Iterator[tuple[str, str, str, Mapping[str, Any]]]:
    """``(group, owner, key, quantity block)`` of each shown quantity of an estimate document, in table order."""
    for group, key in keys:
        for owner, quantities in document.get(group, {}).items():
            block = quantities.get(key)
            if isinstance(block, Mapping):
                yield group, owner, key, block


def quantity_cells(block: Mapping[str, Any]) -> str:
    """``estimate  +- std`` of a quantity block, right-aligned in 10 and 9 characters (blank where missing)."""
    value, std = block.get("value"), block.get("std")
    if value is None:
        return f"{'-':>10s} {'':>9s}"
    return f"{value:10.4f} {'' if std is None else format(std, '9.2g'):>9s}"


def state_line(document: Mapping[str, Any], warming_up: bool) -> str:
    """VALID, a warm-up that is expected, or INVALID (a real problem), with the estimator's message."""
    quality = document["quality"]
    if quality["valid"]:
        return f"VALID: {quality.get('message', '')}"
    if warming_up:
        return (
            "warming up (expected: the window is still filling, and every joint must have moved both ways): "
            f"{quality.get('message', '')}"
        )
    return f"INVALID: {quality.get('message', '')}"


def support_line(wrench_yzx: Sequence[float] | None, support_fraction: float | None = None) -> str:
    """One line on the weight support: the latest ``bsp/weight_support`` wrench ``[F_y (N), F_z (N), M_x (Nm)]``
    on the hand in ``world``, or that none is published (no valid estimate, or no support asked for)."""
    share = "" if support_fraction is None else f" ({support_fraction:g} of the arm's gravity torques)"
    if wrench_yzx is None:
        return f"weight support{share}: none yet (no valid estimate)"
    f_y, f_z, m_x = wrench_yzx
    return (
        f"weight support{share}, on the hand in world: "
        f"F_y {f_y:+.2f} N, F_z {f_z:+.2f} N, M_x {m_x:+.3f} Nm (follows the arm's posture)"
    )
