"""Model check: friction larger at low speed than at high speed (Stribeck-like)."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.unmodelled import MODEL_CHECK_P, MODEL_CHECK_SHIFT_SD, term_test
from bsp_ros.core.identification.stacked import Fit, Problem, normal_equations
from bsp_ros.core.streams import joints_for

# Candidate speeds (rad/s) of a Stribeck-like excess of friction at low speed, sign(v) exp(-(v / v_s)^2).
STRIBECK_SPEEDS_RAD_S = (0.002, 0.004, 0.008, 0.016, 0.032)


def stribeck_check(
    data: IdentificationData, problem: Problem, fit: Fit, config: JointConfig, widths: np.ndarray
) -> list[str]:
    """Friction that is larger at low speed than at high speed (Stribeck-like), joint by joint: the Coulomb
    amplitude of a sign step is then a speed-dependent average, not the joint's friction. Joints with a
    modelled smooth transition (``widths`` > 0) are left out: a tanh step plus a low-speed bump fit direction
    errors near reversals, and the transition's uncertainty is already in their Coulomb variance."""
    if "coulomb" not in config.passive.terms:
        return []
    n, k = data.n_joints, len(config.passive.local)
    w = np.where(problem.rows, fit.weights[None, :], 0.0)
    design, moment, _ = normal_equations(problem, fit.weights)
    notes = []
    for j, joint in enumerate(joints_for(n)):
        if widths[j] > 0:
            continue
        speed = np.abs(data.velocity_rad_s[:, j])
        column = n + j * k + config.passive.local.index("coulomb")
        # The speed by a profile on the bordered normal equations (O(N) per candidate), then one full fit.
        best_gain, best_speed = 0.0, 0.0
        for speed_s in STRIBECK_SPEEDS_RAD_S:
            c = np.sign(data.velocity_rad_s[:, j]) * np.exp(-((speed / speed_s) ** 2)) * w[:, j]
            cross = problem.regressor[:, j, :].T @ c
            cc = float(c @ (c / np.where(w[:, j] > 0, w[:, j], 1.0)))
            a = np.block([[design, cross[:, None]], [cross[None, :], np.array([[cc]])]])
            rhs = np.append(moment, float(c @ problem.torque[:, j]))
            try:
                gain = float(rhs @ np.linalg.solve(a, rhs)) - float(moment @ np.linalg.solve(design, moment))
            except np.linalg.LinAlgError:
                continue
            if gain > best_gain:
                best_gain, best_speed = gain, speed_s
        if best_speed == 0.0:
            continue
        extra = np.zeros((data.t_ns.size, n, 1))
        extra[:, j, 0] = np.sign(data.velocity_rad_s[:, j]) * np.exp(-((speed / best_speed) ** 2))
        p_value, shift, _, wide = term_test(problem, fit, extra, [("stribeck_nm", joint)], [column])
        # Only an excess of friction at low speed is Stribeck-like; a deficit is what direction-of-motion
        # errors near reversals (e.g. around marker gaps) look like, and the transition test covers it.
        if wide.values[-1] > 0 and p_value < MODEL_CHECK_P and shift > MODEL_CHECK_SHIFT_SD:
            notes.append(
                f"friction at the {joint} depends on speed (Stribeck-like, larger below about "
                f"{1e3 * best_speed:.2g} mrad/s): modelling it moves its Coulomb amplitude by {shift:.1f} std; the "
                "amplitude of a sign step is a speed-dependent average here"
            )
    return notes
