"""Model check: friction larger at low speed than at high speed (Stribeck-like)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.unmodelled import (
    MODEL_CHECK_P,
    MODEL_CHECK_SHIFT_SD,
    TermTest,
    shift_bound_sd,
    shifts_sd,
    term_test,
)
from bsp_ros.core.identification.stacked import Fit, Problem, candidate_products, normal_equations
from bsp_ros.core.streams import joints_for

# A Coulomb amplitude moved by at most this many std is weakly identified (its std takes the shift); beyond it the
# estimate is invalid. Skin markers 3 mm off their centres moved it by 1.2-1.9 std; a wrench 12 ms late by 5.1.
STRIBECK_WIDEN_MAX_SD = 3.0
# Candidate speeds (rad/s) of a Stribeck-like excess of friction at low speed, sign(v) exp(-(v / v_s)^2).
STRIBECK_SPEEDS_RAD_S = (0.002, 0.004, 0.008, 0.016, 0.032)


@dataclass(frozen=True)
class StribeckFinding:
    """A joint whose friction is larger at low speed: what modelling it moves.

    Attributes
    ----------
    joint : index of the joint.
    coulomb_column : index of its Coulomb amplitude among the fit's parameters.
    coulomb_shift_nm : how far the low-speed term moves that amplitude (Nm).
    static_shift_sd : the largest shift of a static moment, in std (the larger of the two fits').
    note : the warning, in words.
    coulomb_shift_sd : the Coulomb amplitude's shift in its std.
    """

    joint: int
    coulomb_column: int
    coulomb_shift_nm: float
    static_shift_sd: float
    note: Finding

    coulomb_shift_sd: float

    @property
    def biases_estimate(self) -> bool:
        """Whether no honest std covers it: a static moment moves by more than its std, or the Coulomb amplitude
        by more than a weakly identified amplitude would (then the friction law itself is wrong, and what makes
        it look so, e.g. a wrench stream late against the markers, biases more than friction)."""
        return self.static_shift_sd > MODEL_CHECK_SHIFT_SD or self.coulomb_shift_sd > STRIBECK_WIDEN_MAX_SD


def stribeck_check(
    data: IdentificationData, problem: Problem, fit: Fit, config: JointConfig, widths: np.ndarray
) -> list[StribeckFinding]:
    """Friction that is larger at low speed than at high speed (Stribeck-like), joint by joint: the Coulomb
    amplitude of a sign step is then a speed-dependent average, not the joint's friction. Joints with a
    modelled smooth transition (``widths`` > 0) are left out: a tanh step plus a low-speed bump fit direction
    errors near reversals, and the transition's uncertainty is already in their Coulomb variance.

    A finding that moves only the Coulomb amplitude is a weakly identified amplitude (its std should hold the
    shift, e.g. where skin markers off their joint centres bend the torques near reversals); one that moves a
    static moment by more than its std is a bias no std covers."""
    if "coulomb" not in config.passive.terms:
        return []
    n = data.n_joints
    w = np.where(problem.rows, fit.weights[None, :], 0.0)
    design, moment, _ = normal_equations(problem, fit.weights)
    notes = []
    for j, joint in enumerate(joints_for(n)):
        if widths[j] > 0:
            continue
        column = config.passive.local_column("coulomb", n, j)
        best_speed = _best_stribeck_speed(data, problem, w[:, j], design, moment, j)
        if best_speed == 0.0:
            continue
        test = _stribeck_test(data, problem, fit, j, joint, column, best_speed)
        if test is None:
            continue
        notes.append(_stribeck_finding(problem, fit, test, j, joint, column, best_speed))
    return notes


def _best_stribeck_speed(
    data: IdentificationData, problem: Problem, w_j: np.ndarray, design: np.ndarray, moment: np.ndarray, j: int
) -> float:
    """The candidate speed whose low-speed term best reduces joint ``j``'s misfit, by a profile on the bordered
    normal equations.

    Parameters
    ----------
    data : the samples.
    problem : the stacked problem.
    w_j : the fit's weight of joint ``j`` on each sample, 0 off its used rows; shape (N,).
    design, moment : the normal equations ``A + P`` (p, p) and ``X^T W y + P theta_0`` (p,) of the fit.
    j : index of the joint.

    Returns
    -------
    float
        The best of :data:`STRIBECK_SPEEDS_RAD_S`, rad/s; 0.0 when no candidate reduces the misfit or the normal
        equations are singular.
    """
    speed = np.abs(data.velocity_rad_s[:, j])
    # The speed by a profile on the bordered normal equations, every candidate's column at once (one BLAS
    # product over the used rows), then one full fit.
    used = problem.rows[:, j, None]  # the fit's weights are positive: its weighted rows
    x_j, y_j = problem.joint_rows(j)  # 0 off the used rows
    speeds = np.asarray(STRIBECK_SPEEDS_RAD_S)
    bumps = np.sign(data.velocity_rad_s[:, j, None]) * np.exp(-((speed[:, None] / speeds[None, :]) ** 2))
    bumps = np.where(used, bumps, 0.0)
    crosses, squares, targets = candidate_products(x_j, w_j, y_j, bumps)
    try:
        base = float(moment @ np.linalg.solve(design, moment))
    except np.linalg.LinAlgError:
        return 0.0
    best_gain, best_speed = 0.0, 0.0
    for m, speed_s in enumerate(STRIBECK_SPEEDS_RAD_S):
        a = np.block([[design, crosses[:, m, None]], [crosses[None, :, m], np.array([[squares[m]]])]])
        rhs = np.append(moment, targets[m])
        try:
            gain = float(rhs @ np.linalg.solve(a, rhs)) - base
        except np.linalg.LinAlgError:
            continue
        if gain > best_gain:
            best_gain, best_speed = gain, speed_s
    return best_speed


def _stribeck_test(
    data: IdentificationData, problem: Problem, fit: Fit, j: int, joint: str, column: int, best_speed: float
) -> TermTest | None:
    """The full fit with one joint's low-speed term, watching its Coulomb amplitude and the static moments.

    Parameters
    ----------
    data : the samples.
    problem, fit : the stacked problem and its fit.
    j, joint : the joint's index and name.
    column : index of its Coulomb amplitude among the fit's parameters.
    best_speed : the low-speed term's speed, rad/s (:func:`_best_stribeck_speed`).

    Returns
    -------
    TermTest or None
        The term's test when it is significant and moves a watched parameter beyond its std; None otherwise.
    """
    n = data.n_joints
    speed = np.abs(data.velocity_rad_s[:, j])
    extra = np.zeros((data.t_ns.size, n, 1))
    extra[:, j, 0] = np.sign(data.velocity_rad_s[:, j]) * np.exp(-((speed / best_speed) ** 2))
    watched = [column, *range(n)]

    def can_count(values: np.ndarray, watched: list[int] = watched) -> bool:
        # Only an excess of friction at low speed is Stribeck-like; a deficit is what direction-of-motion
        # errors near reversals (e.g. around marker gaps) look like, and the transition test covers it.
        return bool(values[-1] > 0 and shift_bound_sd(fit, values, watched).max() > MODEL_CHECK_SHIFT_SD)

    test = term_test(problem, fit, extra, [("stribeck_nm", joint)], watched, can_count)
    if test is None or not (test.p_value < MODEL_CHECK_P and test.shift_sd > MODEL_CHECK_SHIFT_SD):
        return None
    return test


def _stribeck_finding(
    problem: Problem, fit: Fit, test: TermTest, j: int, joint: str, column: int, best_speed: float
) -> StribeckFinding:
    """What a significant low-speed term moves, as a finding.

    Parameters
    ----------
    problem, fit : the stacked problem and its fit.
    test : the term's test (:func:`_stribeck_test`).
    j, joint : the joint's index and name.
    column : index of its Coulomb amplitude among the fit's parameters.
    best_speed : the low-speed term's speed, rad/s.

    Returns
    -------
    StribeckFinding
        Which parameter the term moves most, the Coulomb amplitude's shift in Nm and in std, and the largest
        shift of a static moment in std.
    """
    n = problem.rows.shape[1]
    shift, worst, wide = test.shift_sd, test.worst, test.wide
    static_shift = float(shifts_sd(fit, wide, list(range(n))).max())
    coulomb_shift = float(wide.values[column] - fit.values[column])
    coulomb_sd = float(shifts_sd(fit, wide, [column])[0])
    if worst != column:
        moves = "static_moment"
    elif coulomb_sd > STRIBECK_WIDEN_MAX_SD:
        moves = "coulomb"
    else:
        moves = "coulomb_in_std"
    values = {
        "speed_mrad_s": float(1e3 * best_speed),
        "moves": moves,
        "segment": problem.names[worst][1],
        "shift_sd": float(shift),
        "coulomb_shift_nm": coulomb_shift,
        "coulomb_sd": coulomb_sd,
    }
    return StribeckFinding(
        j,
        column,
        coulomb_shift,
        static_shift,
        Finding(code=FindingCode.FRICTION_SPEED_DEPENDENT, where=joint, values=values),
        coulomb_sd,
    )
