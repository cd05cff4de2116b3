"""What skin markers off their joint centres do to an estimate: its covariance, and the residual they explain."""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np

from bsp_ros.core.identification.covariance import design_inverse
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.placement_reweighting import (
    OffsetStatistics,
    reweighted_placement_covariance,
    used_variance,
)
from bsp_ros.core.identification.placement import placement_columns
from bsp_ros.core.identification.result import ParameterName
from bsp_ros.core.identification.stacked import Fit, Problem, augmented, joint_products, reweighted_values

# The handle force the offset columns move is the mean of the other measured torques within this long (s): short,
# so that it follows the force of a fast session (over 0.5 s the columns of the paper's sines at 0.12 rad/s missed
# 4-5 % of what an offset does, and the free offsets read the rest as 2-3 times the placement).
AVERAGE_S = 0.05


@dataclass(frozen=True)
class PlacementEffect:
    """The effect of marker placement on one fit.

    Attributes
    ----------
    covariance : (p, p) of the estimate, from offsets of ``sd_m`` per axis, the fit's per-joint weights following
        them (placement_reweighting.py).
    residual : (N, n) the residual (Nm, NaN where unused) of the fit that also takes marker offsets, each with a
        prior of its ``sd_m``: what is left once offsets of that size explain what they can.
    columns : (N, n, m) the offsets' columns it was computed from (:func:`offset_columns`).
    products : (p, m) ``X^T W D`` of the fit's weights and those columns (:func:`covariance_from_products`).
    statistics : what the covariance is computed from, for the same offsets scaled (:func:`covariance_scaled`).
    """

    covariance: np.ndarray
    residual: np.ndarray
    columns: np.ndarray
    products: np.ndarray
    statistics: OffsetStatistics

    def covariance_scaled(self, column_factor: np.ndarray) -> np.ndarray:
        """(p, p) the covariance from the offsets with each column times ``column_factor`` (m,)."""
        return reweighted_placement_covariance(self.statistics, column_factor)


def offset_columns(data: IdentificationData, problem: Problem, fit: Fit, sd_m: np.ndarray) -> np.ndarray:
    """(N, n, 2 (n + 1)) how an offset of one sd of each marker (``sd_m``, (n + 1,) m) moves the torque equation at
    this fit (``placement_columns``, scaled).

    The handle force the offsets move comes from the measured torques of the neighbouring samples
    (:func:`averaged_torques`), not from each sample's own: that carries the wrench noise into the columns, where it
    correlates with the residual's own (errors in variables). On a simulated session with every marker on its joint
    centre, offsets fitted on the raw torques came out 6-8 sd from zero, the same on every seed
    (``test_placement_scale.py``). The measured torques keep the force where the model's own torques would not (a
    model that misfits).
    """
    n = data.n_joints
    if len(problem.names) >= 3 * n and problem.names[-1][0] == "grouped_inertia_kgm2":
        base_values = np.concatenate((fit.values[:n], fit.values[-2 * n :]))
    else:
        base_values = np.concatenate((fit.values[:n], np.zeros(2 * n)))
    zeros = np.zeros_like(data.q_rad)
    qd = zeros if data.qd_rad_s is None else data.qd_rad_s
    qdd = zeros if data.qdd_rad_s2 is None else data.qdd_rad_s2
    columns = placement_columns(data.q_rad, qd, qdd, data.lengths_m, averaged_torques(data), base_values)
    columns = columns * np.repeat(np.asarray(sd_m, dtype=np.float64), 2)
    return _per_recording(columns, data.recording_index if data.markers_moved else None)


def averaged_torques(data: IdentificationData) -> np.ndarray:
    """(N, n) the measured torques, each the centred mean of the OTHER samples within :data:`AVERAGE_S` (fewer at
    a recording's ends).

    A sample is left out of its own mean: with it, its noise weighs 1/k in the column and correlates with the same
    noise in the residual. Along an offset no data can tell from the parameters (every marker moved along the
    chain scales every torque, as the static moments do) the column's only part the parameters do not explain is
    that averaged noise, and the fit then reads the chain as twice its length: a 2-segment arm with its markers
    on the joint centres came out 30 cm off in that direction, the placement 10 times the assumed one."""
    tau = np.asarray(data.tau_nm, dtype=np.float64)
    if tau.shape[0] < 3:
        return tau
    period_s = float(np.median(np.diff(data.t_ns))) * 1e-9
    half = int(0.5 * AVERAGE_S / period_s) if period_s > 0 else 0
    if half < 1:
        return tau
    out = np.empty_like(tau)
    index = data.recording_index
    bounds = [0, tau.shape[0]] if index is None else [0, *(np.flatnonzero(np.diff(index)) + 1).tolist(), tau.shape[0]]
    for start, stop in itertools.pairwise(bounds):
        part = tau[start:stop]
        sums = np.concatenate((np.zeros((1, part.shape[1])), np.cumsum(part, axis=0)))
        k = np.arange(part.shape[0])
        lo, hi = np.maximum(k - half, 0), np.minimum(k + half + 1, part.shape[0])
        count = (hi - lo - 1)[:, None]
        others = sums[hi] - sums[lo] - part
        out[start:stop] = np.where(count > 0, others / np.maximum(count, 1), part)
    return out


def offset_names(m: int) -> list[ParameterName]:
    """The parameter names of ``m`` marker-offset columns fitted beside a problem's own (each in units of its sd)."""
    return [(f"marker_offset_{k}_sd", "markers") for k in range(m)]


def _with_offsets(problem: Problem, columns: np.ndarray) -> Problem:
    """``problem`` with the offsets' columns (N, n, m) beside its own, each offset in units of its sd (the columns
    are scaled) with the prior N(0, 1)."""
    m = columns.shape[2]
    return augmented(problem, columns, offset_names(m), np.zeros(m), np.ones(m))


def _per_recording(columns: np.ndarray, recording_index: np.ndarray | None) -> np.ndarray:
    """(N, n, m) offset columns shared by every sample or, for recordings whose markers moved between them,
    (N, n, m R): each recording's own.

    Recordings of one visit share their markers; a marker re-attached between them sits elsewhere in each, and a
    second trunk posture separates gravity from elastic moments by the recordings' differences, which shared
    offsets cancel and re-placed ones do not (measured: re-placed within 3 mm, a forearm static moment 3.4 std
    off with one shared placement). The segment lengths tell that a marker moved (``markers_moved``).
    """
    if recording_index is None:
        return columns
    recordings = np.unique(recording_index)
    if recordings.size < 2:
        return columns
    own = [np.where((recording_index == r)[:, None, None], columns, 0.0) for r in recordings]
    return np.concatenate(own, axis=2)


def covariance_from_columns(problem: Problem, fit: Fit, columns: np.ndarray) -> np.ndarray:
    """Covariance (p, p) of the estimate from offsets of unit variance along ``columns`` (N, n, m)."""
    return covariance_from_products(fit, joint_products(problem, fit.weights, columns))


def covariance_from_products(fit: Fit, products: np.ndarray) -> np.ndarray:
    """Covariance (p, p) of the estimate from offsets of unit variance whose columns ``D`` give ``X^T W D`` (p, m)
    at the fit's weights: the response ``G = (A + P)^-1 X^T W D``, then ``G G^T``."""
    response = design_inverse(fit.design) @ products
    return np.asarray(response @ response.T)


def placement_covariance(
    data: IdentificationData, problem: Problem, fit: Fit, sd_m: np.ndarray, base_variance: np.ndarray | None = None
) -> np.ndarray:
    """Covariance (p, p) of the estimate from where the skin markers sit relative to the joint centres.

    Each marker's offset (along and normal to its segment, ``sd_m[k]`` m each for chain point k, shoulder to
    contact point, independent) moves the lever arms
    and the segment angles the fit is computed on; the estimate responds linearly, ``G = (A + P)^-1 X^T W D``.
    Part of this cannot be told from the parameters by any data (offsets along the chain scale every lever
    arm, hence every torque, like the static moments and friction amplitudes themselves), so it is not
    estimated: it is a known uncertainty of every session, different every day, and belongs in the std.

    ``base_variance`` (n,), Nm^2: each joint's residual variance were the markers on their centres; given, the
    fit's per-joint weights follow the offsets (placement_reweighting.py); None: the linear response at the fit's
    weights.
    """
    columns = offset_columns(data, problem, fit, sd_m)
    if base_variance is None:
        return covariance_from_columns(problem, fit, columns)
    with_offsets = _with_offsets(problem, columns)
    assert with_offsets.statistics is not None  # augmented() computes them
    statistics = OffsetStatistics.of(problem, with_offsets.statistics, base_variance, fit.weights * fit.sigma**2)
    return reweighted_placement_covariance(statistics)


def placement_effect(data: IdentificationData, problem: Problem, fit: Fit, sd_m: np.ndarray) -> PlacementEffect:
    """:func:`placement_covariance`, and the residual once offsets of that size (a Gaussian prior, ``sd_m``) have
    taken what they can explain: they also bend the torques in ways the model cannot follow (over a wide planned
    range, at the wrist), and a residual that offsets of a few mm explain is no misfit of the model."""
    columns = offset_columns(data, problem, fit, sd_m)
    # The offsets fitted with the parameters (not on the residual alone: much of their effect resembles a change
    # of the parameters, and only together do they explain it), each with its prior N(0, sd^2).
    with_offsets = _with_offsets(problem, columns)
    residual = np.where(problem.rows, reweighted_values(with_offsets).residual(with_offsets), np.nan)
    # X^T W D from the wider problem's per-joint products of the used rows (its statistics): no second pass.
    assert with_offsets.statistics is not None  # augmented() computes them
    p = len(problem.names)
    products = np.tensordot(fit.weights, with_offsets.statistics[0][:, :p, p:], axes=1)
    # Conditional on the fit's own residual variances: how far its offsets took each joint's weight.
    statistics = OffsetStatistics.of(
        problem, with_offsets.statistics, used_variance(problem, residual), fit.weights * fit.sigma**2, fit.sigma**2
    )
    covariance = reweighted_placement_covariance(statistics)
    return PlacementEffect(covariance, residual, columns, products, statistics)
