"""The elastic passive moment curves of a model choice, with the candidates' spread in their std."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.elastic import ElasticReference, curve_gradients, curve_variance, passive_curves
from bsp_ros.core.identification.planarity import planar_error_nm
from bsp_ros.core.identification.selection import Candidate, Selection
from bsp_ros.core.identification.stacked import Fit


@dataclass(frozen=True)
class CurveBasis:
    """What a model choice's passive curves are made of: the curves' gradients in the chosen model's parameters
    (n, K + 1, p), the variance the other candidates and the planar model add to them (n, K + 1), and the range."""

    gradients: np.ndarray
    spread: np.ndarray
    reference: ElasticReference

    def curves(self, fit: Fit) -> dict[str, dict[str, Any]]:
        """The curves of ``fit`` (the chosen model's values and covariance) with this basis's spread."""
        return passive_curves(self.gradients, fit.values, fit.covariance, self.reference, self.spread)


def selection_curves(
    data: IdentificationData, reference: ElasticReference, fit: Fit, selection: Selection | None
) -> dict[str, dict[str, Any]]:
    """Per joint, the elastic passive moment over the measured range with its std (``passive_curve``), the other
    joints at their session means; with a model choice, the candidates' curves join its variance as the
    parameters' do. Empty for a fixed model."""
    basis = curve_basis(data, reference, fit, selection)
    return {} if basis is None else basis.curves(fit)


def curve_basis(
    data: IdentificationData, reference: ElasticReference, fit: Fit, selection: Selection | None
) -> CurveBasis | None:
    """The basis of :func:`selection_curves`; None for a fixed model."""
    if selection is None:
        # A fixed model's curve would carry no uncertainty of its form (a linear spring on a muscle's exponential
        # curve, a two-joint moment it lacks): curves come with the model choice, whose spread their std holds.
        return None

    def curve_of(candidate: Candidate) -> np.ndarray:
        assert candidate.problem is not None
        return curve_gradients(candidate.problem.names, candidate.model.elastic, reference)

    gradients = curve_of(selection.chosen)
    chosen = gradients @ fit.values  # (n, K + 1)
    spread = np.zeros_like(chosen)
    for candidate in selection.open_models:
        assert candidate.fit is not None
        theirs = curve_of(candidate)
        # The candidate's own variance too: a chosen model without elastic terms has a curve of 0 with no variance
        # by assumption, and at one posture a richer candidate's curve level is as uncertain as its confounding
        # with gravity makes it (arm26 at 150 % of gravity, paper protocol: 0 +- 1.7 Nm against a true 5.3 Nm).
        spread = np.maximum(
            spread, (theirs @ candidate.fit.values - chosen) ** 2 + curve_variance(theirs, candidate.fit.covariance)
        )
    if data.out_of_plane is not None and data.out_of_plane.any():
        # The planar model's gravity error where the arm leaves the plane: once a second posture separates the
        # passive moments from gravity, it lands in the curves (arm26's 3.4 deg oblique axes: its elbow curve 7 %
        # off at 5-9 of its std without this term), not in the static moments.
        n = data.n_joints
        error = planar_error_nm(data.q_rad, fit.values[:n], data.out_of_plane)
        points = spread.shape[1] - 1
        spread = spread.copy()
        spread[:, :points] += error[:, None] ** 2
        spread[:, points] += (error / reference.half_range_rad) ** 2
    return CurveBasis(gradients, spread, reference)
