"""Model check: a wrench offset that drifts over the session (an F/T sensor warming up)."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.unmodelled import MODEL_CHECK_P, MODEL_CHECK_SHIFT_SD, term_test
from bsp_ros.core.identification.result import ParameterName
from bsp_ros.core.identification.stacked import Fit, Problem
from bsp_ros.core.model import contact_jacobian


def drift_check(data: IdentificationData, problem: Problem, fit: Fit) -> list[str]:
    """A wrench offset that changes linearly over the session (an F/T sensor drifting with temperature):
    the torques ``-J(q)^T d t`` it adds are tested as extra columns (``d`` along world y, z and x)."""
    n = data.n_joints
    t_s = (data.t_ns - data.t_ns[data.t_ns.size // 2]) / 1e9
    jacobian = contact_jacobian(data.q_rad, data.lengths_m)  # (N, 3, n)
    extra = -np.transpose(jacobian, (0, 2, 1)) * t_s[:, None, None]  # (N, n, 3)
    axes = [k for k, axis in enumerate(("fy", "fz", "mx")) if np.linalg.norm(extra[:, :, k]) > 0]
    names: list[ParameterName] = [(f"drift_{('fy', 'fz', 'mx')[k]}", "sensor") for k in axes]
    p_value, shift, worst, wide = term_test(problem, fit, extra[:, :, axes], names, list(range(n)))
    if p_value >= MODEL_CHECK_P:
        return []
    rate = np.zeros(3)
    rate[axes] = wide.values[len(problem.names) :]
    span_s = float(t_s[-1] - t_s[0])
    # A drifting sensor's offset at any moment is unknown (a tare holds at the moment it was taken): what the
    # offset changes over the session alone moves the static moments by this much, as a constant offset would.
    w = np.where(problem.rows, fit.weights[None, :], 0.0)
    delta_torque = -np.einsum("tki,k->ti", jacobian, rate * span_s)
    delta = np.linalg.lstsq(fit.design, np.einsum("tip,ti,ti->p", problem.regressor, w, delta_torque), rcond=None)[0]
    std = np.sqrt(np.clip(np.diag(fit.covariance)[:n], 1e-300, None))
    offset_shift = np.abs(delta[:n]) / std
    if max(shift, float(offset_shift.max())) <= MODEL_CHECK_SHIFT_SD:
        return []
    if offset_shift.max() > shift:
        shift, worst = float(offset_shift.max()), int(np.argmax(offset_shift))
    force_rate = float(np.hypot(rate[0], rate[1]))
    return [
        f"the wrench drifts during the session (an F/T sensor offset changing by about {1e3 * force_rate:.2g} mN/s, "
        f"{force_rate * span_s:.2g} N over {span_s:.0f} s): that moves the {problem.names[worst][1]} static moment "
        f"by {shift:.1f} std, and no tare holds for the whole session; let the sensor warm up, re-tare and record again"
    ]
