"""Our default identification: all joints in one weighted, bounded least-squares problem."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.stats import chi2

from bsp_ros.core.dynamics import base_regressor
from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.identification.covariance import correlation_from_covariance
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.elastic import ElasticReference, curve_gradients, passive_curves
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.placement import placement_columns
from bsp_ros.core.identification.priors import BasePrior, base_prior_for_subject, implausible_perpendicular_moments
from bsp_ros.core.identification.result import IdentificationResult, ParameterName
from bsp_ros.core.identification.robust import hampel_outliers, high_frequency_sd, robust_sd
from bsp_ros.core.identification.selection import Candidate, Selection, select_passive, spread_covariance
from bsp_ros.core.identification.stacked import (
    Extras,
    Fit,
    Problem,
    augmented,
    build_problem,
    fit_problem,
    normal_equations,
    problem_names,
)
from bsp_ros.core.model import contact_jacobian
from bsp_ros.core.streams import joints_for, segments_for
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_scalar, check_positive


@dataclass(frozen=True)
class JointConfig:
    """Settings of the stacked identification.

    Attributes
    ----------
    passive : the passive moment model (Coulomb by default).
    deadband_fraction : rows of a joint whose direction speed is below this fraction of its typical speed
        are left out of the fit: there the sign of the motion, hence the Coulomb term, is ambiguous.
    deadband_noise_sd : and rows below this many standard deviations of the velocity noise.
    min_samples : fewer usable samples make the estimate invalid.
    min_range_deg : a joint moving less than this has no excitation (invalid).
    min_direction_share : each direction of motion must hold this share of a joint's rows (Coulomb).
    max_condition : a larger column-scaled condition number makes the estimate invalid.
    check_elastic : test whether an elastic term the model lacks would change the static moments.
    outlier_sd : torque samples further than this many robust standard deviations from the rolling median
        of their neighbours (wrench spikes), or from the fit, are removed.
    spike_window : samples in that rolling median.
    max_misfit : the residual RMS of a joint above this multiple of the sensor noise the data shows
        (robust, from first differences) means the model does not fit: invalid.
    max_outlier_shift : if removing the samples far off the fit moves a parameter by more than this many
        standard deviations, the estimate hangs on a few samples: invalid.
    min_row_share : with a Coulomb term, a joint whose direction of motion is trustworthy in fewer than
        this share of the samples makes the estimate invalid.
    confounded_corr, confounded_rel_std : a passive term is reported confounded with gravity when its
        correlation with a static moment exceeds ``confounded_corr`` and that static moment is uncertain by
        more than ``confounded_rel_std`` of its value: a high correlation alone is harmless when the session
        pins both down (a planned protocol), and the warning says what the confounding costs.
    dynamics : the full rigid-body model: inertial torques of the static moments, perpendicular first
        moments and grouped inertias, the latter two with Gaussian priors (``base_prior``; the default
        subject's anthropometric prior when None), so that what the data cannot tell keeps its prior
        uncertainty in the std instead of being taken as zero.
    marker_placement_sd_m : how far (1 sd, m, per axis) a skin marker may sit from its joint centre: what
        such offsets would move the estimate by joins its covariance (0: markers taken as exact).
    elastic_fallback : when the elastic check finds an elastic passive moment the model lacks, identify again
        with the elastic terms chosen by the data (``--passive auto``) instead of returning an invalid estimate:
        what `bsp identify` does when no passive model was asked for.
    """

    passive: PassiveModel = field(default_factory=PassiveModel)
    deadband_fraction: float = 0.1
    deadband_noise_sd: float = 4.0
    min_samples: int = 200
    min_range_deg: float = 0.2
    min_direction_share: float = 0.05
    max_condition: float = 1e4
    check_elastic: bool = True
    outlier_sd: float = 8.0
    spike_window: int = 11
    max_misfit: float = 4.0
    min_row_share: float = 0.5
    max_outlier_shift: float = 2.0
    confounded_corr: float = 0.95
    confounded_rel_std: float = 0.01
    dynamics: bool = True
    base_prior: BasePrior | None = None
    marker_placement_sd_m: float = 0.002
    elastic_fallback: bool = False

    def __post_init__(self) -> None:
        check_finite_scalar("deadband_fraction", self.deadband_fraction, 0.0, 0.9)
        check_finite_scalar("deadband_noise_sd", self.deadband_noise_sd, 0.0, 100.0)
        check_positive("min_samples", self.min_samples)
        check_finite_scalar("min_range_deg", self.min_range_deg, 0.0, 90.0)
        check_finite_scalar("min_direction_share", self.min_direction_share, 0.0, 0.5)
        check_positive("max_condition", self.max_condition)
        check_positive("outlier_sd", self.outlier_sd, 1000.0)
        check_positive("spike_window", self.spike_window, 10_001)
        check_positive("max_misfit", self.max_misfit)
        check_finite_scalar("min_row_share", self.min_row_share, 0.0, 1.0)
        check_finite_scalar("max_outlier_shift", self.max_outlier_shift, 0.0, 1e6)
        check_finite_scalar("confounded_corr", self.confounded_corr, 0.0, 1.0)
        check_finite_scalar("confounded_rel_std", self.confounded_rel_std, 0.0, 1e6)
        check_finite_scalar("marker_placement_sd_m", self.marker_placement_sd_m, 0.0, 0.05)


def _motion_rows(data: IdentificationData, config: JointConfig) -> tuple[np.ndarray, list[str]]:
    """Rows with a trustworthy direction of motion (all rows when the model has no Coulomb term)."""
    speed = np.abs(data.velocity_rad_s)
    if "coulomb" not in config.passive.terms:
        return np.ones_like(speed, dtype=bool), []
    typical = np.percentile(speed, 95, axis=0)
    noise = np.nan_to_num(data.velocity_noise_rad_s, nan=0.0)
    deadband = np.maximum(config.deadband_fraction * typical, config.deadband_noise_sd * noise)
    notes = []
    for j, joint in enumerate(joints_for(data.n_joints)):
        if noise[j] > 0 and config.deadband_noise_sd * noise[j] > 0.5 * typical[j]:
            notes.append(
                f"uncertain direction of motion at the {joint}: velocity noise {noise[j]:.2g} rad/s against "
                f"a typical speed of {typical[j]:.2g} rad/s"
            )
    return speed > deadband[None, :], notes


def _excitation_problems(data: IdentificationData, rows: np.ndarray, config: JointConfig) -> list[str]:
    problems = []
    if data.t_ns.size < config.min_samples:
        problems.append(f"too few samples: {data.t_ns.size} < {config.min_samples}")
        return problems
    range_deg = np.degrees(np.ptp(data.q_rad, axis=0))
    for j, joint in enumerate(joints_for(data.n_joints)):
        if range_deg[j] < config.min_range_deg:
            problems.append(f"no motion at the {joint}: range {range_deg[j]:.3f} deg < {config.min_range_deg} deg")
        elif "coulomb" in config.passive.terms:
            signs = np.sign(data.velocity_rad_s[rows[:, j], j])
            share = min((signs > 0).mean(), (signs < 0).mean()) if signs.size else 0.0
            if share < config.min_direction_share:
                problems.append(f"the {joint} moved in one direction only ({100 * share:.1f}% of rows the other way)")
    return problems


def _elastic_check(
    data: IdentificationData,
    config: JointConfig,
    rows: np.ndarray,
    base: Fit,
    widths: np.ndarray,
    extras: Extras | None = None,
) -> list[str]:
    """Warn when a linear spring (offset, stiffness) the model lacks is supported by the data and moves the static
    moments: the fixed model would then be valid and wrong (with ``config.elastic_fallback`` the warning says the
    estimate uses the elastic terms the data choose instead)."""
    # A linear spring only. Polynomial terms tested against a model without a spring fit the smallest systematic
    # errors (of the angle filters, on noise-free data) against a gravity torque they can mimic; tested against a
    # fixed spring model, on our own simulator's linear springs with the dynamics, they were "supported" (chi2
    # ~200) and moved the upper arm's static moment by 30 %. Either would throw right estimates away;
    # `--passive auto` weighs them instead, with the spread in the std.
    if "stiffness" in config.passive.terms:
        return []
    wider = config.passive.with_terms(("offset", "stiffness"))
    kinds = " and ".join(term for term in wider.terms if term not in config.passive.terms)
    problem = build_problem(data, wider, rows, widths, extras)
    fit = fit_problem(problem)
    n = data.n_joints
    notes = []
    base_beta, wide_beta = base.values[:n], fit.values[:n]
    change = np.abs(wide_beta - base_beta) / np.maximum(np.abs(base_beta), 1e-9)
    # Against the base fit's std (marker placement included): a shift well inside it cannot make it wrong.
    shift_sd = np.abs(wide_beta - base_beta) / np.sqrt(np.clip(np.diag(base.covariance)[:n], 1e-300, None))
    correlation = correlation_from_covariance(fit.covariance)
    have = set(problem_names(config.passive, n, extras is not None))
    for joint in joints_for(n):
        picks = [i for i, name in enumerate(problem.names) if name[1] == joint and name not in have and i >= n]
        if not picks:
            continue
        sub = fit.covariance[np.ix_(picks, picks)]
        theta = fit.values[picks]
        statistic = float(theta @ np.linalg.pinv(sub) @ theta)
        if chi2.sf(statistic, len(picks)) < 1e-4 and change.max() > 0.005 and shift_sd.max() > MODEL_CHECK_SHIFT_SD:
            worst = int(np.argmax(shift_sd))
            corr = float(np.max(np.abs(correlation[np.ix_(picks, range(n))])))
            notes.append(
                f"elastic passive moment at the {joint}: {kinds} terms the model lacks are supported by "
                f"the data (chi2 {statistic:.0f}) and confounded with gravity (|corr| {corr:.2f}); modelling them "
                f"moves the {problem.names[worst][1]} static moment by {100 * change[worst]:.1f}% "
                f"({shift_sd[worst]:.1f} std): "
                + (
                    "the estimate uses the elastic terms the data choose (--passive auto), and what that choice "
                    "leaves open is in its std"
                    if config.elastic_fallback
                    else "the static moments may be biased (try --passive auto, which chooses the elastic terms and "
                    "puts what the choice leaves open in the std"
                )
                + "; an F/T sensor offset no tare removed looks like an elastic offset: apply one with --tare"
                + ("" if config.elastic_fallback else ")")
            )
    return notes


# Above this column-scaled condition number no std is meaningful: parameters the motion cannot tell apart.
UNIDENTIFIABLE_CONDITION = 1e8


# Torque deviations and misfits below this never count (Nm): no rehab cell's sensor resolves them, and a
# noise-free simulation would otherwise be judged against its rounding errors.
MIN_OUTLIER_NM = 1e-3


# Candidate widths of a smooth friction transition, tanh(v / w) (rad/s): 0.25 to 16 mrad/s.
TRANSITION_WIDTHS_RAD_S = 0.00025 * 2.0 ** (np.arange(25) / 4.0)
# A smooth transition is detected when it lowers the weighted residual sum of squares by this much (a
# chi-square-like figure, inflated by autocorrelation): clean sessions give at most ~1, sessions with 5%
# marker dropouts (noisy directions at each run's ends) up to ~200 rarely, a 1 mrad/s transition over
# 60 s 110 at the wrist and 1200 at the elbow.
TRANSITION_MIN_GAIN = 100.0


def _transition_widths(
    problem: Problem, fit: Fit, data: IdentificationData, config: JointConfig
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Width of a smooth Coulomb transition at each joint, and how uncertain that leaves the amplitude.

    A profile over :data:`TRANSITION_WIDTHS_RAD_S` (and the sign step, width 0), one joint at a time, on
    the weighted normal equations: swapping one column costs O(N), not a new fit.

    Returns
    -------
    widths : (n,) rad/s; 0 where a sign step fits as well (gain below :data:`TRANSITION_MIN_GAIN`).
    spread : (n,) half the range (Nm) of the Coulomb amplitudes over the widths the data cannot tell from
        the chosen one (residual within :data:`TRANSITION_MIN_GAIN` of it): a model uncertainty the
        covariance of one fit does not hold.
    span : (n,) the full range (Nm) of the Coulomb amplitudes from the sign step to the chosen width: what a
        joint that hardly leaves its transition leaves open (the data then cannot say how wide it is).
    """
    n = data.n_joints
    widths, spread, span = np.zeros(n), np.zeros(n), np.zeros(n)
    if "coulomb" not in config.passive.terms:
        return widths, spread, span
    k = len(config.passive.local)
    w = np.where(problem.rows, fit.weights[None, :], 0.0)
    design, moment, total = normal_equations(problem, fit.weights)

    def solve(a: np.ndarray, b: np.ndarray) -> tuple[float, np.ndarray]:
        try:
            x = np.linalg.solve(a, b)
        except np.linalg.LinAlgError:
            return np.inf, np.full(b.size, np.nan)
        return total - float(b @ x), x

    base, base_x = solve(design, moment)
    for j in range(n):
        column = n + j * k + config.passive.local.index("coulomb")
        x_j, w_j, y_j = problem.regressor[:, j, :], w[:, j], problem.torque[:, j]
        profile = [(base, 0.0, float(base_x[column]))]
        for width in TRANSITION_WIDTHS_RAD_S:
            c = np.tanh(data.velocity_rad_s[:, j] / width)
            a, b = design.copy(), moment.copy()
            cross = (x_j * (w_j * c)[:, None]).sum(axis=0)
            cross[column] = (w_j * c * c).sum()
            a[column, :], a[:, column] = cross, cross
            b[column] = (w_j * c * y_j).sum()
            value, x = solve(a, b)
            profile.append((value, float(width), float(x[column])))
        best = min(profile)
        chosen = best if base - best[0] > TRANSITION_MIN_GAIN else profile[0]
        widths[j] = chosen[1]
        near = [c for value, _, c in profile if value <= chosen[0] + TRANSITION_MIN_GAIN and np.isfinite(c)]
        spread[j] = 0.5 * (max(near) - min(near)) if near else 0.0
        narrower = [c for _, width, c in profile if width <= chosen[1] and np.isfinite(c)]
        span[j] = max(narrower) - min(narrower) if narrower else 0.0
    return widths, spread, span


# An unmodelled term counts when its coefficients differ from 0 at this significance (HAC chi-square) AND
# modelling it moves a static moment or a Coulomb amplitude by more than this many of its std: only then
# would the estimate be wrong beyond its std without it.
MODEL_CHECK_P = 1e-6
MODEL_CHECK_SHIFT_SD = 1.0
# Candidate speeds (rad/s) of a Stribeck-like excess of friction at low speed, sign(v) exp(-(v / v_s)^2).
STRIBECK_SPEEDS_RAD_S = (0.002, 0.004, 0.008, 0.016, 0.032)


def _term_test(
    problem: Problem, fit: Fit, extra: np.ndarray, names: list[ParameterName], watched: list[int]
) -> tuple[float, float, int, Fit]:
    """Fit with the extra columns; return the p-value of their coefficients, the largest shift of a
    ``watched`` parameter in std (the larger of the two fits': the base fit's is the std the estimate reports,
    marker placement included), which one, and the wider fit."""
    wide = fit_problem(augmented(problem, extra, names))
    p = len(problem.names)
    picks = list(range(p, p + len(names)))
    theta = wide.values[picks]
    try:
        statistic = float(theta @ np.linalg.solve(wide.covariance[np.ix_(picks, picks)], theta))
    except np.linalg.LinAlgError:
        return 1.0, 0.0, watched[0], wide
    variance = np.maximum(np.diag(wide.covariance)[watched], np.diag(fit.covariance)[watched])
    shift = np.abs(wide.values[watched] - fit.values[watched]) / np.sqrt(np.clip(variance, 1e-300, None))
    worst = int(np.argmax(shift))
    return float(chi2.sf(statistic, len(picks))), float(shift[worst]), watched[worst], wide


def _drift_check(data: IdentificationData, problem: Problem, fit: Fit) -> list[str]:
    """A wrench offset that changes linearly over the session (an F/T sensor drifting with temperature):
    the torques ``-J(q)^T d t`` it adds are tested as extra columns (``d`` along world y, z and x)."""
    n = data.n_joints
    t_s = (data.t_ns - data.t_ns[data.t_ns.size // 2]) / 1e9
    jacobian = contact_jacobian(data.q_rad, data.lengths_m)  # (N, 3, n)
    extra = -np.transpose(jacobian, (0, 2, 1)) * t_s[:, None, None]  # (N, n, 3)
    axes = [k for k, axis in enumerate(("fy", "fz", "mx")) if np.linalg.norm(extra[:, :, k]) > 0]
    names: list[ParameterName] = [(f"drift_{('fy', 'fz', 'mx')[k]}", "sensor") for k in axes]
    p_value, shift, worst, wide = _term_test(problem, fit, extra[:, :, axes], names, list(range(n)))
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


def _stribeck_check(
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
        p_value, shift, _, wide = _term_test(problem, fit, extra, [("stribeck_nm", joint)], [column])
        # Only an excess of friction at low speed is Stribeck-like; a deficit is what direction-of-motion
        # errors near reversals (e.g. around marker gaps) look like, and the transition test covers it.
        if wide.values[-1] > 0 and p_value < MODEL_CHECK_P and shift > MODEL_CHECK_SHIFT_SD:
            notes.append(
                f"friction at the {joint} depends on speed (Stribeck-like, larger below about "
                f"{1e3 * best_speed:.2g} mrad/s): modelling it moves its Coulomb amplitude by {shift:.1f} std; the "
                "amplitude of a sign step is a speed-dependent average here"
            )
    return notes


def _spikes(data: IdentificationData, config: JointConfig) -> tuple[np.ndarray, list[str]]:
    """Samples whose torques jump off the rolling median of their neighbours (wrench spikes), or not finite."""
    finite = np.isfinite(data.tau_nm).all(axis=1)
    flags = ~finite
    if finite.sum() >= 3:
        flags[finite] = hampel_outliers(
            data.tau_nm[finite], config.spike_window, config.outlier_sd, floor=MIN_OUTLIER_NM
        )
    count = int(flags.sum())
    if not count:
        return flags, []
    return flags, [
        f"removed {count} wrench sample{'s' if count > 1 else ''} off the local robust spread (joint torques more "
        f"than {config.outlier_sd:g} robust sd from the rolling median of {config.spike_window} samples)"
    ]


def _fit_outliers(fit: Fit, config: JointConfig) -> np.ndarray:
    """(N,) samples with a residual beyond ``outlier_sd`` robust standard deviations at any joint."""
    scale = robust_sd(fit.residual, axis=0)
    with np.errstate(invalid="ignore"):
        far = np.abs(fit.residual) > np.maximum(config.outlier_sd * scale, MIN_OUTLIER_NM)[None, :]
    return np.asarray(far.any(axis=1))


# Samples this close to a gap in the data (angles lost to marker dropouts) sit where the direction filter
# has least support; far-off samples there are named as such (seen at 0-0.2 s in simulated dropouts).
GAP_EDGE_S = 0.25


def _near_gaps(t_ns: np.ndarray, edge_s: float) -> np.ndarray:
    """(N,) samples within ``edge_s`` of a gap: consecutive stamps more than 3 median periods apart."""
    near = np.zeros(t_ns.size, dtype=bool)
    if t_ns.size < 3:
        return near
    step = np.diff(t_ns)
    gaps = np.flatnonzero(step > 3 * np.median(step))
    if gaps.size == 0:
        return near
    edges = np.sort(np.concatenate([t_ns[gaps], t_ns[gaps + 1]]))  # the last sample before, first after
    position = np.searchsorted(edges, t_ns)
    before = np.abs(t_ns - edges[np.clip(position - 1, 0, edges.size - 1)])
    after = np.abs(edges[np.clip(position, 0, edges.size - 1)] - t_ns)
    return np.asarray(np.minimum(before, after) <= edge_s * 1e9)


def _misfit(fit: Fit) -> tuple[np.ndarray, np.ndarray]:
    """Per joint: the sensor noise the data shows (Nm) and the residual RMS as a multiple of it."""
    noise = high_frequency_sd(fit.residual)
    rms = np.sqrt(np.nanmean(fit.residual**2, axis=0))
    return noise, rms / np.maximum(noise, 1e-12)


# The elastic offset whose effect on the static moments the estimate states (Nm).
SENSITIVITY_OFFSET_NM = 0.05


def _offset_sensitivity(problem: Problem, fit: Fit, n: int) -> dict[str, dict[str, float]]:
    """Joint -> segment -> how far an unmodelled constant passive offset of 0.05 Nm at that joint moves the
    static moment (kg m), to first order: ``A^-1 X^T W u`` with ``u`` the offset's torque column."""
    joints, segments = joints_for(n), segments_for(n)
    out: dict[str, dict[str, float]] = {}
    if any(key == "offset_nm" for key, _ in problem.names):
        return out  # the offset is modelled: nothing assumed
    w = np.where(problem.rows, fit.weights[None, :], 0.0)
    try:
        for j, joint in enumerate(joints):
            rhs = SENSITIVITY_OFFSET_NM * problem.regressor[:, j, :].T @ w[:, j]
            shift = np.linalg.solve(fit.design, rhs)[:n]
            out[joint] = {segment: float(v) for segment, v in zip(segments, shift, strict=True)}
    except np.linalg.LinAlgError:
        return {}
    return out


def _failed(
    data: IdentificationData, names: list[ParameterName], problems: list[str], warnings: list[str]
) -> IdentificationResult:
    p = len(names)
    return IdentificationResult(
        "joint",
        names,
        np.full(p, np.nan),
        np.full((p, p), np.nan),
        False,
        "; ".join(problems),
        warnings,
        n_samples=int(data.t_ns.size),
    )


def _base_extras(data: IdentificationData, config: JointConfig) -> Extras | None:
    """The dynamics and perpendicular-moment blocks with their priors, or None when the model is static."""
    if not config.dynamics:
        return None
    n = data.n_joints
    zeros = np.zeros_like(data.q_rad)
    qd = zeros if data.qd_rad_s is None else data.qd_rad_s
    qdd = zeros if data.qdd_rad_s2 is None else data.qdd_rad_s2
    prior = config.base_prior or base_prior_for_subject(SubjectInfo(), data.lengths_m)
    if n != prior.inertia_mean_kgm2.size:
        raise InputError(f"the base prior is for {prior.inertia_mean_kgm2.size} segments, the data has {n}")
    return Extras(base_regressor(data.q_rad, qd, qdd, data.lengths_m), prior)


def _placement_covariance(data: IdentificationData, problem: Problem, fit: Fit, sd_m: float) -> np.ndarray:
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


def _curves(
    data: IdentificationData, reference: ElasticReference, fit: Fit, selection: Selection | None
) -> dict[str, dict[str, Any]]:
    """Per joint, the elastic passive moment over the measured range with its std (``passive_curve``), the other
    joints at their session means; with a model choice, the candidates' curves join its variance as the
    parameters' do. Empty for a fixed model."""
    if selection is None:
        # A fixed model's curve would carry no uncertainty of its form (a linear spring on a muscle's exponential
        # curve, a two-joint moment it lacks): curves come with the model choice, whose spread their std holds.
        return {}

    def curve_of(candidate: Candidate) -> np.ndarray:
        assert candidate.problem is not None
        return curve_gradients(candidate.problem.names, candidate.model.elastic, reference)

    gradients = curve_of(selection.chosen)
    chosen = gradients @ fit.values  # (n, K + 1)
    spread = np.zeros_like(chosen)
    for candidate in selection.candidates:
        if candidate.fit is None or candidate is selection.chosen or candidate.rejected:
            continue
        spread = np.maximum(spread, (curve_of(candidate) @ candidate.fit.values - chosen) ** 2)
    return passive_curves(gradients, fit.values, fit.covariance, reference, spread)


def _prior_share(problem: Problem, covariance: np.ndarray) -> dict[str, float]:
    """Posterior / prior variance of every parameter with a prior: near 1, the prior alone decided it."""
    out = {}
    for i in np.flatnonzero(problem.prior_precision > 0):
        key, owner = problem.names[i]
        out[f"{key}/{owner}"] = float(covariance[i, i] * problem.prior_precision[i])
    return out


def identify_joint(data: IdentificationData, config: JointConfig | None = None) -> IdentificationResult:
    """Identify static moments and passive moments of all joints in one stacked problem.

    Wrench spikes are removed before the fit and samples far off the fit after it (counted in the
    warnings); if removing the latter moves a parameter by more than its standard deviation, the
    estimate is not valid: it would hang on a few samples. Nor is it valid when the residuals are far
    above the sensor noise the data shows (the model does not fit), when a static moment sits at its
    bound 0, or when most samples of a joint lie in the direction dead band.

    Parameters
    ----------
    data : samples with joint angles, direction velocities and measured torques.
    config : passive model and validity thresholds.

    Returns
    -------
    IdentificationResult with a HAC covariance; ``valid`` False with a message when excitation is poor.
    """
    config = config or JointConfig()
    n = data.n_joints
    joints = joints_for(n)
    rows, notes = _motion_rows(data, config)
    spikes, spike_notes = _spikes(data, config)
    rows &= ~spikes[:, None]
    problems = _excitation_problems(data, rows, config)
    extras = _base_extras(data, config)
    problem = build_problem(data, config.passive, rows, extras=extras)
    warnings = list(data.warnings) + spike_notes + notes
    if data.t_ns.size < max(config.min_samples, 2 * len(problem.names)) or rows.sum(axis=0).min() < len(problem.names):
        problems = problems or [f"too few usable samples: {int(rows.sum(axis=0).min())}"]
        return _failed(data, problem.names, problems, warnings)
    usable = int((~spikes).sum())
    if "coulomb" in config.passive.terms:
        for j, joint in enumerate(joints):
            share = rows[:, j].sum() / max(usable, 1)
            if share < config.min_row_share:
                problems.append(
                    f"most samples of the {joint} were dropped: only {100 * share:.0f}% move clearly enough to "
                    "tell the direction of motion"
                )
    fit = fit_problem(problem)
    widths, spread, span = _transition_widths(problem, fit, data, config)
    if widths.any():
        problem = build_problem(data, config.passive, rows, widths, extras)
        fit = fit_problem(problem)
        for j, joint in enumerate(joints):
            if widths[j] == 0:
                continue
            beyond = float((np.abs(data.velocity_rad_s[rows[:, j], j]) > 3 * widths[j]).sum()) / max(usable, 1)
            warnings.append(
                f"friction at the {joint} changes direction smoothly (tanh width about {1e3 * widths[j]:.2g} mrad/s, "
                f"modelled); {100 * beyond:.0f}% of samples move faster than 3 widths"
            )
            if beyond < config.min_row_share:
                # Weakly identified, not wrong: every width from the sign step to the chosen one stays plausible,
                # and the amplitudes over them join its std.
                spread[j] = max(spread[j], span[j])
                warnings.append(
                    f"the {joint} hardly leaves its friction transition ({100 * beyond:.0f}% of samples beyond 3 "
                    f"widths): its Coulomb amplitude is weakly identified, and its std says by how much"
                )
    selection = None
    if config.passive.select:
        sd_m = config.marker_placement_sd_m

        def with_placement(candidate: Problem, candidate_fit: Fit) -> np.ndarray:
            if sd_m == 0:
                return candidate_fit.covariance
            return candidate_fit.covariance + _placement_covariance(data, candidate, candidate_fit, sd_m)

        selection = select_passive(data, config.passive, rows, widths if widths.any() else None, extras, with_placement)
        assert selection.chosen.problem is not None and selection.chosen.fit is not None
        config = dataclasses.replace(config, passive=selection.chosen.model)
        problem, fit = selection.chosen.problem, selection.chosen.fit
    far = _fit_outliers(fit, config)
    n_far = int(far.sum())
    n_removed = 0
    if n_far > 0.05 * usable:
        problems.append(
            f"the model does not fit: {n_far} of {usable} samples lie over {config.outlier_sd:g} robust sd off it"
        )
    elif n_far:
        kept = build_problem(data, config.passive, rows & ~far[:, None], widths, extras)
        refit = fit_problem(kept)
        # Against the larger std of the two fits: samples far off the fit (a filter's edge, a glitch) also
        # inflate the std of the fit that keeps them.
        std = np.sqrt(np.clip(np.maximum(np.diag(refit.covariance), np.diag(fit.covariance)), 0.0, None))
        shift = np.abs(refit.values - fit.values) / np.maximum(std, 1e-300)
        near_gap = int((far & _near_gaps(data.t_ns, GAP_EDGE_S)).sum())
        where = (
            f"; {near_gap} of them within {GAP_EDGE_S:g} s of a gap in the joint angles (marker dropouts: the "
            "direction of motion, hence the sign of friction, is least certain there)"
            if near_gap
            else ""
        )
        warnings.append(
            f"removed {n_far} sample{'s' if n_far > 1 else ''} far off the fit (residual over "
            f"{config.outlier_sd:g} robust sd){where}"
        )
        if shift.max() > config.max_outlier_shift:
            worst = int(np.argmax(shift))
            key, owner = problem.names[worst]
            problems.append(
                f"the fit hangs on a few samples: removing {n_far} far off it moves {key} at the {owner} by "
                f"{shift[worst]:.1f} std"
            )
        problem, fit, n_removed = kept, refit, n_far
    if spread.any():
        # Whether friction steps or changes smoothly at low speed is itself uncertain: its effect on each
        # Coulomb amplitude joins that amplitude's variance (independent of the other parameters).
        covariance = fit.covariance.copy()
        k = len(config.passive.local)
        for j in range(n):
            index = n + j * k + config.passive.local.index("coulomb")
            covariance[index, index] += spread[j] ** 2
        fit = dataclasses.replace(fit, covariance=covariance)
    # Whether the data or the prior decided a parameter, judged before the placement uncertainty is added.
    prior_share = _prior_share(problem, fit.covariance)
    if config.marker_placement_sd_m > 0:
        placement = _placement_covariance(data, problem, fit, config.marker_placement_sd_m)
        fit = dataclasses.replace(fit, covariance=fit.covariance + placement)
    model_spread = np.zeros_like(fit.covariance)
    if selection is not None:
        # What the choice of passive model leaves open belongs in the std (model-averaged variance).
        model_spread, model_shift = spread_covariance(selection)
        fit = dataclasses.replace(fit, covariance=fit.covariance + model_spread)
        for index in np.flatnonzero(model_shift[:n] > 0.5).tolist():
            warnings.append(
                f"the {problem.names[index][1]} static moment depends on the passive model the data cannot choose "
                f"between (they differ by up to {model_shift[index]:.1f} of its data std): that spread is in its std"
            )
    reference = ElasticReference.from_angles(data.q_rad)
    curves = _curves(data, reference, fit, selection)
    noise, misfit = _misfit(fit)
    for j, joint in enumerate(joints):
        if misfit[j] > config.max_misfit and misfit[j] * noise[j] > MIN_OUTLIER_NM:
            problems.append(
                f"the model does not fit at the {joint}: residual RMS {misfit[j] * noise[j]:.3g} Nm is "
                f"{misfit[j]:.1f} times the sensor noise ({noise[j]:.2g} Nm) the data shows (a missing or "
                "wrong sensor transform, an unmodelled load or passive moment?)"
            )
    if fit.condition > UNIDENTIFIABLE_CONDITION:
        problems.append(
            f"not identifiable: condition number {fit.condition:.3g} (the motion cannot tell some parameters apart; "
            "move each joint over a wider range: bsp plan)"
        )
    elif fit.condition > config.max_condition:
        # An honest std is large here, not wrong: the estimate stays, its std says what the motion leaves open.
        warnings.append(f"poorly excited: condition number {fit.condition:.3g} > {config.max_condition:g}")
    correlation = correlation_from_covariance(fit.covariance)
    all_std = np.sqrt(np.clip(np.diag(fit.covariance), 0.0, None))
    max_corr_with_gravity = {}
    for i, (key, owner) in enumerate(problem.names[: problem.passive_end]):
        if i >= n:
            partner = int(np.argmax(np.abs(correlation[i, :n])))
            corr = float(abs(correlation[i, partner]))
            max_corr_with_gravity[f"{key}/{owner}"] = corr
            value = fit.values[partner]
            rel_std = all_std[partner] / value if value > 0 else np.inf
            if corr > config.confounded_corr and rel_std > config.confounded_rel_std:
                warnings.append(
                    f"confounded: {key} at the {owner} is correlated with gravity (|corr| {corr:.3f}); the "
                    f"{problem.names[partner][1]} static moment is uncertain by {rel_std:.1%} "
                    "(a session at several operating points separates them: bsp plan)"
                )
        std = all_std[i]
        at_bound = np.isfinite(problem.lower[i]) and fit.values[i] <= problem.lower[i] + 1e-12
        if at_bound and i < n:
            problems.append(f"the {owner} static moment sits at its bound 0: the data do not support it")
        elif at_bound and std > 0:
            warnings.append(f"{key} at the {owner} sits at its bound {problem.lower[i]:g}")
        if i < n and fit.values[i] > 0 and std > 0.5 * fit.values[i]:
            warnings.append(f"uncertain: {owner} static moment {fit.values[i]:.4g} +- {std:.2g} kgm")
    if config.check_elastic and not problems:
        unmodelled = _drift_check(data, problem, fit) + _stribeck_check(data, problem, fit, config, widths)
        warnings += unmodelled
        if unmodelled:
            problems.append("the data show an effect the model lacks that biases the estimate (see warnings)")
    if config.check_elastic and selection is None and not problems:
        elastic = _elastic_check(data, config, problem.rows, fit, widths, extras)
        if elastic and config.elastic_fallback:
            # The data reject the fixed model: the family the data choose from, its spread in the std, replaces it.
            chosen = dataclasses.replace(config.passive, select=True)
            fallback = identify_joint(data, dataclasses.replace(config, passive=chosen, elastic_fallback=False))
            fallback.warnings = elastic + fallback.warnings
            return fallback
        warnings += elastic
        if elastic:
            problems.append(
                "an elastic passive moment the model lacks is supported by the data and biases the static moments "
                "(see warnings)"
            )
    if config.check_elastic and extras is not None and not problems:
        # Last, with the model checks (live, they run beside the updates): a drift or an elastic term the checks
        # above name is the likelier cause of an off-axis moment.
        perpendicular = [i for i, (key, _) in enumerate(problem.names) if key == "perpendicular_moment_kgm"]
        problems += implausible_perpendicular_moments(
            [problem.names[i][1] for i in perpendicular],
            fit.values[perpendicular],
            extras.prior,
            np.sqrt(np.clip(np.diag(model_spread)[perpendicular], 0.0, None)),
        )
    sensitivity = _offset_sensitivity(problem, fit, n)
    valid = not problems and bool(np.isfinite(fit.values).all())
    message = "; ".join(problems) if problems else f"identified from {data.t_ns.size} samples"
    residual_rms = {joint: float(np.sqrt(np.nanmean(fit.residual[:, j] ** 2))) for j, joint in enumerate(joints)}
    used = problem.rows.sum(axis=0)
    removed = {"wrench_spikes": int(spikes.sum()), "fit_outliers": n_removed}
    return IdentificationResult(
        "joint",
        problem.names,
        fit.values,
        fit.covariance,
        valid,
        message,
        warnings,
        fit.condition,
        residual_rms,
        int(data.t_ns.size),
        {
            "hac_lags": fit.lags,
            "max_corr_with_gravity": max_corr_with_gravity,
            "passive_model": config.passive.label,
            "passive_selection": {} if selection is None else selection.to_dict(),
            "passive_curves": curves,
            "elastic_reference": reference.to_dict(),
            "rows_used": {j: int(c) for j, c in zip(joints, used, strict=True)},
            "sensor_noise_nm": {j: float(v) for j, v in zip(joints, noise, strict=True)},
            "misfit_ratio": {j: float(v) for j, v in zip(joints, misfit, strict=True)},
            "removed_samples": {k: v for k, v in removed.items() if v},
            "offset_sensitivity_kgm_per_0_05_nm": sensitivity,
            "friction_transition_rad_s": {j: float(v) for j, v in zip(joints, widths, strict=True)},
            "coulomb_transition_spread_nm": {j: float(v) for j, v in zip(joints, spread, strict=True)},
            "prior_share": prior_share,
        },
    )
