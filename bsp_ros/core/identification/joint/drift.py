"""Model check: a wrench offset that drifts over the session (an F/T sensor warming up), and its model."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.covariance import design_inverse
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.unmodelled import MODEL_CHECK_P, MODEL_CHECK_SHIFT_SD, shift_bound_sd, term_test
from bsp_ros.core.identification.result import ParameterName
from bsp_ros.core.identification.stacked import Fit, Problem, joint_products
from bsp_ros.core.model import contact_jacobian


@dataclass(frozen=True)
class Drift:
    """A drift the data show: what to tell the user, and the fit that models it (the problem's parameters only;
    the drift rates' uncertainty and the unknown offset level's effect in its covariance)."""

    note: Finding
    fit: Fit
    # The wider fit's own covariance of the problem's parameters (without the unknown level's share).
    own_covariance: np.ndarray


@dataclass(frozen=True)
class DriftSpans:
    """Where each recording's drift runs: its rows, its length (s), the drift columns kept, the contact Jacobian."""

    groups: list[np.ndarray]
    spans_s: np.ndarray
    columns: list[int]
    jacobian: np.ndarray  # (N, 3, n)


def drift_columns(data: IdentificationData) -> tuple[np.ndarray, list[ParameterName], DriftSpans]:
    """The torques ``-J(q)^T t`` of a unit drift rate along world y, z and x, one set per recording.

    Returns
    -------
    columns : (N, n, m) the non-zero columns; names : (m,) their parameter names;
    spans : each recording's rows and length (s), which of its 3 columns are kept, the contact Jacobian.
    """
    jacobian = contact_jacobian(data.q_rad, data.lengths_m)  # (N, 3, n)
    groups = (
        [np.arange(data.t_ns.size)]
        if data.recording_index is None
        else [np.flatnonzero(data.recording_index == k) for k in np.unique(data.recording_index)]
    )
    t_s = np.zeros((len(groups), data.t_ns.size))
    spans_s = np.zeros(len(groups))
    for k, rows in enumerate(groups):
        t_s[k, rows] = (data.t_ns[rows] - data.t_ns[rows[rows.size // 2]]) / 1e9
        spans_s[k] = (data.t_ns[rows[-1]] - data.t_ns[rows[0]]) / 1e9
    # (N, n, 3 K): per recording, the torques of a unit drift rate along world y, z and x.
    extra = np.concatenate([-np.transpose(jacobian, (0, 2, 1)) * t[:, None, None] for t in t_s], axis=2)
    columns = [c for c in range(extra.shape[2]) if np.linalg.norm(extra[:, :, c]) > 0]
    label = ("fy", "fz", "mx")
    names: list[ParameterName] = [
        (f"drift_{label[c % 3]}" + (f"_{c // 3 + 1}" if len(groups) > 1 else ""), "sensor") for c in columns
    ]
    return extra[:, :, columns], names, DriftSpans(groups, spans_s, columns, jacobian)


def drift_check(
    data: IdentificationData,
    problem: Problem,
    fit: Fit,
    terms: tuple[np.ndarray, list[ParameterName], DriftSpans] | None = None,
) -> Drift | None:
    """A wrench offset that changes linearly over each recording (an F/T sensor drifting with temperature):
    the torques ``-J(q)^T d t`` it adds are tested as extra columns (``d`` along world y, z and x), one set per
    recording (recordings minutes apart are not one line: between them the sensor may have been re-tared, and a
    second posture's different misfit would pass for a drift across the gap).

    A drift that moves the static moments is modelled, not thrown away: the fit with the drift columns
    replaces ``fit``. Its rate is identified; its level at any moment is not (a tare holds when it was taken,
    and an offset is collinear with gravity at one posture), so the static moments' shift under an offset as
    large as the drift over each recording joins their covariance. ``terms``: :func:`drift_columns` of ``data``,
    when the caller has them."""
    n = data.n_joints
    extra, names, spans = terms or drift_columns(data)
    groups, spans_s, columns, jacobian = spans.groups, spans.spans_s, spans.columns, spans.jacobian
    p = len(problem.names)
    std = np.sqrt(np.clip(np.diag(fit.covariance)[:n], 1e-300, None))

    # The last values' effect: the test's values come again once it went on to the wider fit.
    computed: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def offset_effect(values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The drift rate per recording (along world y, z and x) of a wider fit's ``values``, and how far an offset
        as large as the drift over each recording moves the parameters: a drifting sensor's offset at any moment is
        unknown (a tare holds at the moment it was taken), so that shift is what a constant offset would cause."""
        key = values.tobytes()
        if key not in computed:
            flat_rate = np.zeros(3 * len(groups))
            flat_rate[columns] = values[p:]
            rate = flat_rate.reshape(len(groups), 3)
            delta_torque = np.zeros_like(data.tau_nm)
            for k, rows in enumerate(groups):
                delta_torque[rows] = -np.einsum("tki,k->ti", jacobian[rows], rate[k] * spans_s[k])
            computed.clear()
            computed[key] = rate, design_inverse(fit.design) @ joint_products(problem, fit.weights, delta_torque)
        return computed[key]

    def can_count(values: np.ndarray) -> bool:
        bound = shift_bound_sd(fit, values, list(range(n))).max()
        return bool(max(bound, (np.abs(offset_effect(values)[1][:n]) / std).max()) > MODEL_CHECK_SHIFT_SD)

    test = term_test(problem, fit, extra, names, list(range(n)), can_count)
    if test is None or test.p_value >= MODEL_CHECK_P:
        return None
    shift, worst, wide = test.shift_sd, test.worst, test.wide
    rate, delta = offset_effect(wide.values)
    offset_shift = np.abs(delta[:n]) / std
    if max(shift, float(offset_shift.max())) <= MODEL_CHECK_SHIFT_SD:
        return None
    if offset_shift.max() > shift:
        shift, worst = float(offset_shift.max()), int(np.argmax(offset_shift))
    force_rates = np.hypot(rate[:, 0], rate[:, 1])
    k = int(np.argmax(force_rates))
    covariance = wide.covariance[:p, :p] + np.outer(delta, delta)
    modelled = dataclasses.replace(wide, values=wide.values[:p], covariance=covariance, design=wide.design[:p, :p])
    values = {
        "drift_recording": k + 1 if len(groups) > 1 else 0,
        "rate_mn_s": float(1e3 * force_rates[k]),
        "amount_n": float(force_rates[k] * spans_s[k]),
        "span_s": float(spans_s[k]),
        "segment": problem.names[worst][1],
        "shift_sd": float(shift),
    }
    note = Finding(code=FindingCode.DRIFT_MODELLED, values=values)
    return Drift(note, modelled, wide.covariance[:p, :p])
