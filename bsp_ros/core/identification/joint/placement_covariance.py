"""The covariance of the estimate from where the skin markers sit relative to the joint centres."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.placement import placement_columns
from bsp_ros.core.identification.stacked import Fit, Problem


def placement_covariance(data: IdentificationData, problem: Problem, fit: Fit, sd_m: float) -> np.ndarray:
    """Covariance (p, p) of the estimate from where the skin markers sit relative to the joint centres.

    Each marker's offset (along and normal to its segment, ``sd_m`` each, independent) moves the lever arms
    and the segment angles the fit is computed on; the estimate responds linearly, ``G = (A + P)^-1 X^T W D``.
    Part of this cannot be told from the parameters by any data (offsets along the chain scale every lever
    arm, hence every torque, like the static moments and friction amplitudes themselves), so it is not
    estimated: it is a known uncertainty of every session, different every day, and belongs in the std.
    """
    n = data.n_joints
    if len(problem.names) >= 3 * n and problem.names[-1][0] == "grouped_inertia_kgm2":
        base_values = np.concatenate((fit.values[:n], fit.values[-2 * n :]))
    else:
        base_values = np.concatenate((fit.values[:n], np.zeros(2 * n)))
    zeros = np.zeros_like(data.q_rad)
    qd = zeros if data.qd_rad_s is None else data.qd_rad_s
    qdd = zeros if data.qdd_rad_s2 is None else data.qdd_rad_s2
    columns = placement_columns(data.q_rad, qd, qdd, data.lengths_m, data.tau_nm, base_values)
    w = np.where(problem.rows, fit.weights[None, :], 0.0)
    response = np.linalg.lstsq(fit.design, np.einsum("tip,ti,tim->pm", problem.regressor, w, columns), rcond=None)[0]
    return np.asarray(sd_m**2 * response @ response.T)
