"""Predicted against achieved: how well a session delivered the stds its plan promised."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from bsp_ros.core.identification.result import IdentificationResult
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
