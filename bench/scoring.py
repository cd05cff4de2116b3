"""Scores an estimate document against a simulation's truth: its data-sourced parameters' errors and |z|, both error
rates (two-sided calibration and sharpness: :mod:`calibration`)."""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

from calibration import z_values

DATA_SOURCES = ("data", "data+prior")


def residuals(document: dict[str, Any], truth: dict[str, Any]) -> dict[str, tuple[float, float]]:
    """(value - truth, std) of every data-sourced parameter the truth knows, keyed ``quantity/owner``.

    Parameters
    ----------
    document : dict
        An estimate document (``segments`` and ``joints``, each quantity with ``value``, ``std``, ``source``).
    truth : dict
        The simulation's truth in the same layout (``SimulatedSession.truth.to_dict()``, truth.json).

    Returns
    -------
    dict
        ``quantity/owner -> (signed error, std)`` in the quantity's unit; a missing std is 0. Invalid estimates
        are scored too (their values are what a user who ignored the flag would take); a parameter without a
        value is left out.
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
                out[f"{key}/{owner}"] = (float(value) - float(true), float(std or 0.0))
    return out


def z_scores(document: dict[str, Any], truth: dict[str, Any]) -> dict[str, float]:
    """|value - truth| / std of every parameter :func:`residuals` scores, keyed ``quantity/owner``.

    A parameter with a zero or missing std scores 0 if exact, else infinity.
    """
    return {name: abs(z) for name, z in z_values(residuals(document, truth)).items()}


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
