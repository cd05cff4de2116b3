"""Walking the quantities of an estimate document (``value``, ``std``, ``source``), curves left out."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any


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
