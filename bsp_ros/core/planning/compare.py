"""Predicted against achieved: how well a session delivered the stds its plan promised."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.planning.budget import PredictedBudget
from bsp_ros.core.planning.information import Prediction
from bsp_ros.errors import InputError


def compare_with_result(prediction: Prediction, result: IdentificationResult) -> list[dict[str, Any]]:
    """Per parameter: predicted std, the std the identification reported (HAC), and their ratio.

    Parameters
    ----------
    prediction : from ``predict_covariance`` (or a ``Plan``) for the session's trajectory.
    result : ``identify_joint`` on the session, with the same passive model.

    Returns
    -------
    One dict per parameter: ``quantity``, ``owner``, ``value``, ``predicted_std``, ``achieved_std``,
    ``ratio`` (achieved / predicted).

    Raises
    ------
    InputError
        The two name different parameters (another passive model or chain).
    """
    if list(result.names) != list(prediction.names):
        raise InputError(f"prediction and result differ in parameters: {prediction.names} vs {result.names}")
    rows = []
    for (key, owner), value, predicted, achieved in zip(
        result.names, result.values, prediction.std, result.std, strict=True
    ):
        rows.append(
            {
                "quantity": key,
                "owner": owner,
                "value": float(value),
                "predicted_std": float(predicted),
                "achieved_std": float(achieved),
                "ratio": float(achieved / predicted) if predicted > 0 else float("inf"),
            }
        )
    return rows


def compare_with_scatter(prediction: Prediction, results: Sequence[IdentificationResult]) -> list[dict[str, Any]]:
    """Per parameter: predicted std against the scatter (sample std) of estimates over repeated sessions.

    Returns
    -------
    One dict per parameter: ``quantity``, ``owner``, ``predicted_std``, ``achieved_std`` (sample std over
    the sessions), ``reported_std`` (mean HAC std), ``ratio`` (achieved / predicted).
    """
    if len(results) < 2:
        raise InputError(f"a scatter needs at least 2 sessions, got {len(results)}")
    for result in results:
        if list(result.names) != list(prediction.names):
            raise InputError(f"prediction and result differ in parameters: {prediction.names} vs {result.names}")
    values = np.array([r.values for r in results])
    reported = np.array([r.std for r in results]).mean(axis=0)
    scatter = values.std(axis=0, ddof=1)
    return [
        {
            "quantity": key,
            "owner": owner,
            "predicted_std": float(p),
            "achieved_std": float(a),
            "reported_std": float(r),
            "ratio": float(a / p) if p > 0 else float("inf"),
        }
        for (key, owner), p, a, r in zip(prediction.names, prediction.std, scatter, reported, strict=True)
    ]


def compare_budget_with_estimate(budget: PredictedBudget, estimate: dict[str, Any]) -> list[dict[str, Any]]:
    """Per parameter the plan predicts and the estimate reports: the predicted std against the reported one.

    Parameters
    ----------
    budget : the plan's predicted budget (``Plan.budget``).
    estimate : `bsp identify`'s estimate document of a session that followed the plan (docs/contract.md).

    Returns
    -------
    One dict per parameter in both: ``quantity``, ``owner``, ``predicted_std``, ``reported_std``, ``ratio``
    (reported / predicted), ``predicted_largest`` and ``reported_largest`` (the largest term of each budget).
    A parameter of a model the estimate did not choose (``--passive auto``) is left out.
    """
    rows = []
    for i, (key, owner) in enumerate(budget.names):
        block = estimate["segments" if key == "static_moment_kgm" else "joints"].get(owner, {})
        reported = block.get(key)
        if not isinstance(reported, dict) or reported.get("std") is None:
            continue
        predicted = float(budget.std[i])
        terms: dict[str, float] = reported.get("budget") or {}
        rows.append(
            {
                "quantity": key,
                "owner": owner,
                "predicted_std": predicted,
                "reported_std": float(reported["std"]),
                "ratio": float(reported["std"]) / predicted if predicted > 0 else float("inf"),
                "predicted_largest": budget.largest_term(i)[0],
                "reported_largest": max(terms, key=lambda term: terms[term]) if terms else None,
            }
        )
    return rows
