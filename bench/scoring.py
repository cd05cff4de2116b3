"""Scores an estimate document against a simulation's truth: |z| of its data-sourced parameters, both error rates."""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

DATA_SOURCES = ("data", "data+prior")


def z_scores(document: dict[str, Any], truth: dict[str, Any]) -> dict[str, float]:
    """|value - truth| / std of every data-sourced parameter the truth knows, keyed ``quantity/owner``.

    Invalid estimates are scored too (their values are what a user who ignored the flag would take); a
    parameter without a value is left out, one with a zero or missing std scores 0 if exact, else infinity.
    """
    out = {}
    for group in ("segments", "joints"):
        for owner, quantities in document.get(group, {}).items():
            for key, q in quantities.items():
                if not isinstance(q, dict) or q.get("source") not in DATA_SOURCES:
                    continue
                true = truth.get(group, {}).get(owner, {}).get(key)
                value, std = q.get("value"), q.get("std")
                if not isinstance(true, (int, float)) or value is None:
                    continue
                error = abs(float(value) - float(true))
                out[f"{key}/{owner}"] = error / std if std else (0.0 if error == 0.0 else math.inf)
    return out


def verdict(valid: bool, max_z: float) -> str:
    """``valid-and-wrong`` (valid, some |z| > 3), ``invalid-and-right`` (invalid, every |z| <= 3), else ``ok``."""
    if math.isnan(max_z):
        return "ok"
    if valid and max_z > 3.0:
        return "valid-and-wrong"
    if not valid and max_z <= 3.0:
        return "invalid-and-right"
    return "ok"


def rates(verdicts: Iterable[str]) -> tuple[int, int, int]:
    """(runs, valid-and-wrong, invalid-and-right) of a list of :func:`verdict` results."""
    items = list(verdicts)
    return len(items), items.count("valid-and-wrong"), items.count("invalid-and-right")
