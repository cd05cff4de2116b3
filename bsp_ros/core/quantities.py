"""Walking an estimate document: its quantities (``value``, ``std``, ``source``) and, apart, its passive curves."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

# ``joints.<joint>.passive_curve``: a curve (``angle_deg``, ``moment_nm``, ``std_nm``...), not a quantity.
PASSIVE_CURVE = "passive_curve"


def is_quantity(entry: Any) -> bool:
    """Whether a segment's or joint's entry is a quantity (``value``, ``std``, ``source``), not a curve."""
    return isinstance(entry, dict) and "value" in entry and "source" in entry


def quantities_of(document: dict[str, Any]) -> Iterator[tuple[str, str, str, dict[str, Any]]]:
    """``(group, owner, key, quantity)`` for every quantity of an estimate document, curves left out."""
    for group in ("segments", "joints"):
        for owner, entries in document.get(group, {}).items():
            for key, entry in entries.items():
                if is_quantity(entry):
                    yield group, owner, key, entry


def passive_curves_of(document: dict[str, Any]) -> Iterator[tuple[str, dict[str, Any]]]:
    """``(joint, curve)`` for every joint of an estimate document that has a passive curve."""
    for joint, entries in document.get("joints", {}).items():
        curve = entries.get(PASSIVE_CURVE)
        if isinstance(curve, dict):
            yield joint, curve
