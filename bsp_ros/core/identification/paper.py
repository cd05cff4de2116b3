"""The method paper's procedure, faithfully: wrist, then elbow, then shoulder; passive moments by Eq. 11."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode, note
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.excitation import excitation_problems, motion_rows
from bsp_ros.core.identification.joint.grip import direction_share
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.result import IdentificationResult, ParameterName
from bsp_ros.core.identification.stacked import bounded_least_squares
from bsp_ros.core.methods import Method
from bsp_ros.core.model import GRAVITY_M_S2, absolute_angles_rad, running_sum
from bsp_ros.core.streams import joints_for, segments_for
from bsp_ros.validation import check_finite_scalar, check_positive


@dataclass(frozen=True)
class PaperConfig:
    """Bounds of Eq. 10.

    Attributes
    ----------
    passive_bound_nm : the passive term of each pi_j is bounded to +-this ("set to values around zero",
        Sect. 2.2); the passive moment then comes from Eq. 11.
    max_static_moment_kgm, max_mass_kg : upper bounds of the static moments and masses (lower bounds 0).
    """

    passive_bound_nm: float = 1e-6
    max_static_moment_kgm: float = 5.0
    max_mass_kg: float = 20.0

    def __post_init__(self) -> None:
        check_finite_scalar("passive_bound_nm", self.passive_bound_nm, 0.0, 100.0)
        check_positive("max_static_moment_kgm", self.max_static_moment_kgm)
        check_positive("max_mass_kg", self.max_mass_kg)


def _bounded_fit(columns: np.ndarray, target: np.ndarray, upper: np.ndarray, passive_bound: float) -> np.ndarray:
    lower = np.zeros(columns.shape[1])
    lower[-1], upper = -passive_bound, upper.copy()
    upper[-1] = passive_bound
    return bounded_least_squares(columns, target, lower, upper)


def identify_paper(data: IdentificationData, config: PaperConfig | None = None) -> IdentificationResult:
    """Sequential bounded least squares of Eq. 6-10 and the passive moments of Eq. 11.

    The paper's parameters ``pi_3 = [m3 l3, tau_p3]``, ``pi_2 = [m2 l2, m3, tau_p2]``,
    ``pi_1 = [m1 l1, m2, tau_p1]`` are solved joint by joint from the wrist, each step using the previous
    results. ``m2`` and ``m3`` are not identifiable from gravity (their columns are proportional to the
    static-moment columns), so the bounded solver's split is arbitrary: only the grouped static moments of
    docs/contract.md are reported as data. Standard deviations are classical per-joint least-squares errors,
    ignoring the error carried down the chain and residual autocorrelation, as the paper does.

    Parameters
    ----------
    data : samples with joint angles and measured torques.
    config : the bounds of Eq. 10.

    Returns
    -------
    IdentificationResult with method ``"paper"``; the split values are in ``diagnostics["paper_pi"]``.
    """
    config = config or PaperConfig()
    n = data.n_joints
    a = data.lengths_m
    fits = _sequential_fit(data, config)
    pi = fits.pi
    beta = [pi["m1l1"] + a[0] * (pi["m2"] + pi["m3"]), pi["m2l2"] + (a[1] * pi["m3"] if n == 3 else 0.0)]
    if n == 3:
        beta.append(pi["m3l3"])
    names: list[ParameterName] = [("static_moment_kgm", s) for s in segments_for(n)] + [
        ("coulomb_nm", j) for j in joints_for(n)
    ]
    values = np.array(beta + list(fits.passive_nm))
    n_samples = int(data.t_ns.size)
    # Eq. 11's mean |residual| has the standard error of a mean of |r|.
    passive_std = [float(np.std(np.abs(r))) / np.sqrt(n_samples) for r in _residuals(data, values, n)]
    covariance = np.diag(np.concatenate((fits.static_std_kgm, passive_std)) ** 2)
    return IdentificationResult(
        method=Method.PAPER,
        names=names,
        values=values,
        covariance=covariance,
        findings=_paper_findings(data, n_samples, len(names), values),
        summary=f"identified from {n_samples} samples (sequential, Eq. 6-11)",
        residual_rms_nm=fits.residual_rms_nm,
        n_samples=n_samples,
        diagnostics={"paper_pi": {k: float(v) for k, v in pi.items()}},
    )


@dataclass(frozen=True, kw_only=True)
class _SequentialFit:
    """The joint-by-joint fits of Eq. 6-10 and what Eq. 11 makes of their residuals.

    Attributes
    ----------
    pi : the paper's split parameters by name (``m1l1``, ``m2``, ``m2l2``, ``m3``, and ``m3l3`` for a
        3-segment arm), kg m and kg.
    passive_nm : each joint's passive moment, the mean absolute residual of Eq. 11, Nm; shape (n,).
    static_std_kgm : each joint's classical std of its static-moment column, kg m; shape (n,).
    residual_rms_nm : each joint's rms residual, Nm, by joint name.
    """

    pi: dict[str, float]
    passive_nm: np.ndarray
    static_std_kgm: np.ndarray
    residual_rms_nm: dict[str, float]


def _sequential_fit(data: IdentificationData, config: PaperConfig) -> _SequentialFit:
    """Eq. 6-8 solved by bounded least squares from the wrist (Eq. 6) through the elbow (Eq. 7) to the shoulder
    (Eq. 8), each step taking the previous steps' values; Eq. 11 on each step's residual.

    Parameters
    ----------
    data : samples with joint angles and measured torques.
    config : the bounds of Eq. 10.
    """
    n = data.n_joints
    a = data.lengths_m
    g_cos = GRAVITY_M_S2 * np.cos(absolute_angles_rad(data.q_rad))  # (N, n): g cos(phi_j)
    ones = np.ones(data.t_ns.size)
    pi: dict[str, float] = {}
    passive, static_std, residual_rms = np.zeros(n), np.zeros(n), {}
    joints = joints_for(n)

    def finish(j: int, columns: np.ndarray, target: np.ndarray, solution: np.ndarray) -> None:
        residual = target - columns @ solution
        passive[j] = float(np.mean(np.abs(residual)))  # Eq. 11
        # Classical error of the identifiable (first) column, Coulomb stripped by Eq. 11's magnitude.
        sigma = float(np.std(np.abs(residual)))
        static_std[j] = sigma / float(np.linalg.norm(columns[:, 0]))
        residual_rms[joints[j]] = float(np.sqrt(np.mean(residual**2)))

    bound_m, bound_s = config.max_mass_kg, config.max_static_moment_kgm
    if n == 3:  # wrist, Eq. 6
        cols = np.column_stack((g_cos[:, 2], ones))
        target = data.tau_nm[:, 2]
        sol = _bounded_fit(cols, target, np.array([bound_s, 0.0]), config.passive_bound_nm)
        pi["m3l3"] = sol[0]
        finish(2, cols, target, sol)
    # elbow, Eq. 7: the 2-segment arm has no m3 column and its forearm ends at the contact point
    m3l3 = pi.get("m3l3", 0.0)
    if n == 3:
        cols = np.column_stack((g_cos[:, 1], a[1] * g_cos[:, 1], ones))
        target = data.tau_nm[:, 1] - g_cos[:, 2] * m3l3
        sol = _bounded_fit(cols, target, np.array([bound_s, bound_m, 0.0]), config.passive_bound_nm)
        pi["m2l2"], pi["m3"] = sol[0], sol[1]
    else:
        cols = np.column_stack((g_cos[:, 1], ones))
        target = data.tau_nm[:, 1]
        sol = _bounded_fit(cols, target, np.array([bound_s, 0.0]), config.passive_bound_nm)
        pi["m2l2"], pi["m3"] = sol[0], 0.0
    finish(1, cols, target, sol)
    # shoulder, Eq. 8
    m3, m2l2 = pi["m3"], pi["m2l2"]
    cols = np.column_stack((g_cos[:, 0], a[0] * g_cos[:, 0], ones))
    distal = a[0] * g_cos[:, 0] * m3 + (a[1] * g_cos[:, 1] * m3 if n == 3 else 0.0) + g_cos[:, 1] * m2l2
    if n == 3:
        distal = distal + g_cos[:, 2] * m3l3
    target = data.tau_nm[:, 0] - distal
    sol = _bounded_fit(cols, target, np.array([bound_s, bound_m, 0.0]), config.passive_bound_nm)
    pi["m1l1"], pi["m2"] = sol[0], sol[1]
    finish(0, cols, target, sol)
    return _SequentialFit(pi=pi, passive_nm=passive, static_std_kgm=static_std, residual_rms_nm=residual_rms)


def _paper_findings(
    data: IdentificationData, n_samples: int, n_parameters: int, values: np.ndarray
) -> tuple[Finding, ...]:
    """The findings of a paper identification: too few samples for its ``n_parameters`` parameters, values not
    finite (``values``, shape (p,)) or a motion that cannot tell them (:func:`_excitation_problems`), the data's
    notes, and the method's two caveats (an arbitrary split, classical standard deviations)."""
    problems = []
    if n_samples < 2 * n_parameters:
        problems.append(Finding(code=FindingCode.TOO_FEW_SAMPLES))
    elif not np.isfinite(values).all():
        problems.append(Finding(code=FindingCode.NON_FINITE))
    else:
        problems.extend(_excitation_problems(data, 2 * n_parameters))
    return (
        *problems,
        *(note(FindingCode.DATA_NOTE, w) for w in data.warnings),
        Finding(code=FindingCode.PAPER_SPLIT_ARBITRARY),
        Finding(code=FindingCode.PAPER_STD_CLASSICAL),
    )


def _excitation_problems(data: IdentificationData, min_samples: int) -> list[Finding]:
    """A joint that did not move (``no_motion``), moved in one direction only (``one_direction``) or too slowly
    to tell its direction in most samples (``direction_unclear``): the joint method's checks, at the paper's own
    sample minimum. Eq. 11 reads the passive moment off the residual's magnitude and Eq. 6-8 the static moment
    off the change of ``cos(phi)``: a still joint gives neither, and friction in one direction only is a constant
    the gravity column takes up."""
    config = JointConfig(passive=PassiveModel.parse("coulomb"), min_samples=min_samples)
    rows, _ = motion_rows(data, config)
    problems = excitation_problems(data, rows, config)
    judged = {finding.where for finding in problems}
    for j, joint in enumerate(joints_for(data.n_joints)):
        share = direction_share(rows[:, j], int(data.t_ns.size), None)
        if joint not in judged and share < config.min_row_share:
            values = {"share_percent": float(100 * share)}
            problems.append(Finding(code=FindingCode.DIRECTION_UNCLEAR, where=joint, values=values))
    return problems


def _residuals(data: IdentificationData, values: np.ndarray, n: int) -> list[np.ndarray]:
    """Per-joint torque residuals of the gravity part alone (what Eq. 11 averages)."""
    g_cos = GRAVITY_M_S2 * np.cos(absolute_angles_rad(data.q_rad))
    beta = values[:n]
    gravity = running_sum(g_cos * beta, reverse=True)
    return [data.tau_nm[:, j] - gravity[:, j] for j in range(n)]
