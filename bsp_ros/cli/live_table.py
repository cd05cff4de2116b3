"""A live estimate as terminal lines, shared by `bsp demo` (beside the simulated truth) and `bsp watch` (any cell).

Light at import (the standard library only): the `bsp` parser imports every subcommand module at start. The callers
read the received JSON into an :class:`~bsp_ros.core.estimate_schema.Estimate` (``Estimate.from_json``) at the edge.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from bsp_ros.core.estimate_schema import Estimate, Quantity

__all__ = ["ROW_KEYS", "estimate_rows", "quantity_cells", "state_line", "support_line"]

#: The quantities a live table shows: each segment's static moment (what gravity pulls through, what a robot
#: carries) and each joint's Coulomb friction (the passive moment that resists motion).
ROW_KEYS: tuple[tuple[str, str], ...] = (("segments", "static_moment_kgm"), ("joints", "coulomb_nm"))


def estimate_rows(
    estimate: Estimate, keys: Sequence[tuple[str, str]] = ROW_KEYS
) -> Iterator[tuple[str, str, str, Quantity]]:
    """``(group, owner, key, quantity)`` of each shown quantity of an estimate, in table order (``group``:
    ``segments`` or ``joints``)."""
    for group, key in keys:
        owners = estimate.segments if group == "segments" else estimate.joints
        for owner, quantities in owners.items():
            quantity = quantities.get(key)
            if quantity is not None:
                yield group, owner, key, quantity


def quantity_cells(quantity: Quantity) -> str:
    """``estimate  +- std`` of a quantity, right-aligned in 10 and 9 characters (blank where missing)."""
    value, std = quantity.value, quantity.std
    if value is None:
        return f"{'-':>10s} {'':>9s}"
    return f"{value:10.4f} {'' if std is None else format(std, '9.2g'):>9s}"


def state_line(estimate: Estimate, warming_up: bool) -> str:
    """VALID, a warm-up that is expected, or INVALID (a real problem), with the estimator's message."""
    message = estimate.quality.message
    if estimate.valid:
        return f"VALID: {message}"
    if warming_up:
        return (
            f"warming up (expected: the window is still filling, and every joint must have moved both ways): {message}"
        )
    return f"INVALID: {message}"


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
