"""The uncertainty budget `bsp identify` will report for a session that follows a plan, term by term.

The estimate's std is not the sensor noise's alone (docs/method.md, "The uncertainty budget"): the marker
placement, the sensor's zero and, with ``--passive auto`` or a nonlinear model, the model choice add their own
terms, and on a planned (precise) session they dominate. The prediction builds the session's samples as the
estimator will see them, noise-free, from the plan's motion and the nominal arm, and runs identify's own
functions on them: its problem (rows, columns, priors: ``motion_rows``, ``base_extras``, ``build_problem``), its
placement propagation (``placement_covariance``) and its response to a sensor offset (``TorqueResponse``,
``offset_torques_nm``, ``zero_covariance``), at the weights the predicted sensor noise gives. The sensor-noise
term is the information matrix's sandwich on those same columns (``information.py``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint import JointConfig
from bsp_ros.core.identification.joint.excitation import motion_rows
from bsp_ros.core.identification.joint.extras import base_extras
from bsp_ros.core.identification.joint.placement_covariance import offset_columns, placement_covariance
from bsp_ros.core.identification.joint.torque_response import TorqueResponse
from bsp_ros.core.identification.ledger import Ledger, Term
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.priors import base_prior_for_subject
from bsp_ros.core.identification.recordings import combine_recordings
from bsp_ros.core.identification.result import ParameterName
from bsp_ros.core.identification.sensitivity import offset_torques_nm, zero_covariance
from bsp_ros.core.identification.stacked import Fit, Problem, build_problem, joint_products, problem_names
from bsp_ros.core.joint_angles import KinematicsConfig
from bsp_ros.core.model import gravity_regressor
from bsp_ros.core.pipeline import IdentifyOptions
from bsp_ros.core.planning.choice import ScoreCovariance, expected_choice_variance
from bsp_ros.core.planning.information import (
    PREDICTION_GRID_HZ,
    NoiseSpec,
    NominalArm,
    Trajectory,
    covariance_terms,
    information_products,
    predicted_model,
    sample_noise,
)
from bsp_ros.errors import InputError

__all__ = [
    "DURATION_FREE_TERMS",
    "NOMINAL_BIARTICULAR_NM",
    "NOMINAL_COULOMB_NM",
    "NOMINAL_STIFFENING_NM",
    "NOMINAL_STIFFNESS_NM_PER_RAD",
    "TYPICAL_TARE_S",
    "PredictedBudget",
    "SessionSpec",
    "nominal_passive_truth",
    "predict_budget",
]

#: The nominal arm's dry friction (shoulder, elbow, wrist), Nm: the simulated cell's (the paper's human results).
#: It is in the nominal torques, hence in the handle force the placement columns move.
NOMINAL_COULOMB_NM = (0.5, 0.28, 0.06)
#: The relaxed arm's joint springs (shoulder, elbow, wrist), Nm/rad: of the order the literature reports and the
#: MuJoCo benchmark cell uses. Where the model has elastic terms they are in the nominal torques: the placement
#: term moves with the passive moments' size (the upper arm's static moment: 0.020 kg m without springs, 0.031
#: with these; a simulated session with them reported 0.029-0.030).
NOMINAL_STIFFNESS_NM_PER_RAD = (0.30, 0.50, 0.15)
#: Their stiffening (``sinh`` about the neutral angle over 0.5 rad), Nm, and a two-joint muscle across shoulder and
#: elbow, Nm: a real arm's passive moments are nonlinear and coupled (in the nominal torques of a nonlinear model).
NOMINAL_STIFFENING_NM = (0.10, 0.05, 0.01)
NOMINAL_BIARTICULAR_NM = 0.05
#: A tare recording's length, s: the simulated cell's (``TareSpec``). Averaged at rest it leaves the zero uncertain by
#: the wrench noise over ``sqrt(rate x length)`` (`bsp tare` of 120 s at 0.05 N, 100 Hz: 0.46 mN, as that says).
TYPICAL_TARE_S = 20.0
#: Terms a longer session of the same motion does not shrink: they come from where things sit, not from noise.
DURATION_FREE_TERMS = (Term.MARKER_PLACEMENT, Term.SENSOR_ZERO)
# Recordings at several trunk tilts are this far apart in time (ns): distinct, as in a cell.
_RECORDING_GAP_NS = 600_000_000_000


@dataclass(frozen=True)
class SessionSpec:
    """How the plan's sessions will be recorded and identified: what their std holds beside the sensor noise.

    Attributes
    ----------
    identify : `bsp identify`'s options the std depends on: ``marker_placement_sd_m`` and ``handle_pose_sd_m``
        (m, 1 sd per axis), ``zero_sd_n`` (N) and ``zero_sd_nm`` (Nm) of an untared sensor, and ``subject`` (the
        prior of the perpendicular moments and inertias). Its ``passive`` and ``tare`` are not read.
    tared : the session will be identified with a tare (``--tare FILE``): the zero's uncertainty is a tare's of
        :data:`TYPICAL_TARE_S` at rest, not ``zero_sd_n``/``zero_sd_nm``.
    contact_from_robot : the contact point will come from the robot's handle pose (``handle_pose_sd_m``), not a
        skin marker (``marker_placement_sd_m``).
    """

    identify: IdentifyOptions = field(default_factory=IdentifyOptions)
    tared: bool = False
    contact_from_robot: bool = False

    def zero_sd(self, noise: NoiseSpec) -> tuple[float, float]:
        """The sensor zero's 1 sd per axis, (N, Nm): a tare's (its noise averaged) or the assumed one."""
        if self.tared:
            draws = np.sqrt(noise.wrench_hz * TYPICAL_TARE_S)
            return noise.force_noise_n / draws, noise.torque_noise_nm / draws
        return self.identify.zero_sd_n, self.identify.zero_sd_nm

    def to_dict(self, noise: NoiseSpec) -> dict[str, Any]:
        """The assumptions as a JSON-ready dict (the plan file's ``uncertainty``)."""
        zero_n, zero_nm = self.zero_sd(noise)
        return {
            "marker_placement_sd_m": self.identify.marker_placement_sd_m,
            "handle_pose_sd_m": self.identify.handle_pose_sd_m,
            "contact_from_robot": self.contact_from_robot,
            "tared": self.tared,
            "zero_sd": {"force_n": zero_n, "moment_nm": zero_nm},
        }


@dataclass(frozen=True)
class PredictedBudget:
    """The predicted std of each reported parameter as a ledger of identify's named terms.

    Attributes
    ----------
    names : (p,) the parameters, in the estimator's order (static moments, passive terms).
    ledger : the predicted covariance (p, p) term by term.
    nominal : (p,) nominal values (NaN where none is assumed).
    """

    names: list[ParameterName]
    ledger: Ledger
    nominal: np.ndarray

    @property
    def covariance(self) -> np.ndarray:
        """(p, p) the predicted covariance: the sum of the terms."""
        return self.ledger.total(len(self.names))

    @property
    def std(self) -> np.ndarray:
        """(p,) the predicted std of each parameter, in its unit."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    def std_of(self, quantity: str, owner: str) -> float:
        """The predicted std of one parameter."""
        return float(self.std[self.names.index((quantity, owner))])

    def contributions(self, index: int) -> dict[str, float]:
        """Each term's standard uncertainty of parameter ``index`` (the std is the root of their squares' sum)."""
        return self.ledger.contributions(index)

    def largest_term(self, index: int) -> tuple[str, float]:
        """The term with the largest share of parameter ``index``'s std, and its standard uncertainty."""
        term, sd = max(self.contributions(index).items(), key=lambda item: item[1])
        return term, sd

    def duration_free_std(self) -> np.ndarray:
        """(p,) the std of the terms a longer session does not shrink (:data:`DURATION_FREE_TERMS`)."""
        kept = Ledger(tuple((term, c) for term, c in self.ledger if term in DURATION_FREE_TERMS))
        return np.sqrt(np.clip(np.diag(kept.total(len(self.names))), 0.0, None))

    @property
    def max_relative_static_std(self) -> float:
        """Largest predicted std / nominal value over the static moments."""
        picks = [i for i, (key, _) in enumerate(self.names) if key == "static_moment_kgm"]
        return float(np.max(self.std[picks] / np.abs(self.nominal[picks])))

    def table(self) -> list[dict[str, Any]]:
        """One row per parameter: ``quantity``, ``owner``, ``std``, ``nominal``, ``relative_std``, ``budget``
        (term -> standard uncertainty) and ``largest_term``."""
        rows = []
        for i, ((key, owner), sd, value) in enumerate(zip(self.names, self.std, self.nominal, strict=True)):
            finite = bool(np.isfinite(value) and value != 0)
            rows.append(
                {
                    "quantity": key,
                    "owner": owner,
                    "std": float(sd),
                    "nominal": float(value) if np.isfinite(value) else None,
                    "relative_std": float(sd / abs(value)) if finite else None,
                    "budget": self.contributions(i),
                    "largest_term": self.largest_term(i)[0],
                }
            )
        return rows


def predict_budget(
    trajectory: Trajectory,
    duration_s: float,
    nominal: NominalArm,
    passive: PassiveModel,
    noise: NoiseSpec | None = None,
    session: SessionSpec | None = None,
    kinematics: KinematicsConfig | None = None,
    trunk_tilts_rad: Sequence[float] = (0.0,),
    grid_hz: float = PREDICTION_GRID_HZ,
    open_models: Sequence[PassiveModel] = (),
) -> PredictedBudget:
    """Predict the std `bsp identify` will report, term by term, for a session that follows ``trajectory``.

    Parameters
    ----------
    trajectory : the joint motion relative to the trunk.
    duration_s : each recording's length, s.
    nominal : the assumed arm (lengths, static moments).
    passive : the passive model identify will fit (``auto``: its richest candidate, probed as identify does).
    noise : sensor noise (default ``NoiseSpec()``).
    session : identify's placement and zero assumptions, and whether the session is tared.
    kinematics : the angle filters identify uses.
    trunk_tilts_rad : one recording per trunk posture (rad), identified together.
    grid_hz : evaluation grid, Hz; each grid sample stands for the wrench samples around it.
    open_models : with ``passive`` the model ``--passive auto`` chooses (:class:`~.choice.AutoChoice`), the other
        candidates its data cannot reject: the model-choice term is then the expected spread identify adds
        (:func:`~.choice.expected_choice_variance`), on an arm with the cell's nonlinear, coupled passive moments.

    Returns
    -------
    PredictedBudget with the terms ``sensor_noise``, ``marker_placement`` (where a placement sd is assumed),
    ``model_choice`` (``open_models``, or a nonlinear model's shape probe) and ``sensor_zero``.
    """
    noise = noise or NoiseSpec()
    session = session or SessionSpec()
    kinematics = kinematics or KinematicsConfig()
    model = predicted_model(passive)
    # With auto's choice the arm is the cell's (nonlinear, coupled passive moments), whatever model was chosen.
    elastic, nonlinear = "offset" in model.terms or bool(open_models), "nonlinear" in model.terms or bool(open_models)
    truth = nominal_passive_truth(trajectory, duration_s, nominal.n_joints, elastic=elastic, nonlinear=nonlinear)
    data = nominal_data(trajectory, duration_s, nominal, truth, noise, kinematics, trunk_tilts_rad, grid_hz)
    options = session.identify
    config = JointConfig(passive=model, base_prior=base_prior_for_subject(options.subject, data.lengths_m))
    # identify's rows (its direction deadband) and columns; not its spike filter, which on noise-free torques
    # takes each Coulomb reversal for a spike.
    rows, _ = motion_rows(data, config)
    extras = base_extras(data, config)
    problem = build_problem(data, model, rows, None, extras)
    probe = None
    if "nonlinear" in model.terms and "higher" not in model.terms and not open_models:
        # identify probes a nonlinear model's shape (identification.selection.shape_probe): its columns extend
        # the model's, so one pass gives both.
        probe = build_problem(data, model.with_terms(("higher",)), rows, None, extras)
    fit, ledger = _noise_terms(data, problem, probe, nominal, noise, kinematics, grid_hz)
    sd_m = options.placement_sd_m(data)
    if sd_m.any():
        # The nominal samples' residual is the noise alone: the weights follow the offsets from there, as identify's.
        placement = placement_covariance(data, problem, fit, sd_m, fit.sigma**2)
        ledger = ledger.plus(Term.MARKER_PLACEMENT, placement)
    zero_cov = zero_covariance(*session.zero_sd(noise))
    response = TorqueResponse(problem, fit.weights, fit.design, np.ones(fit.values.size, dtype=bool))
    offsets = response.columns(offset_torques_nm(data, np.eye(3)))
    zero = offsets @ zero_cov @ offsets.T
    ledger = ledger.plus(Term.SENSOR_ZERO, 0.5 * (zero + zero.T))
    if open_models:
        union = build_problem(data, _union_model(model, open_models), rows, None, extras)
        scores = _score_covariance(data, union, fit, sd_m, zero_cov, noise, kinematics, nominal, grid_hz)
        choice = expected_choice_variance(scores, problem.names, _open_names(model, open_models, data, extras))
        ledger = ledger.plus(Term.MODEL_CHOICE, np.diag(choice))
    reported = problem.passive_end  # the static moments and passive terms; not the priors' perpendicular moments
    kept = Ledger(tuple((term, c[:reported, :reported]) for term, c in ledger))
    values = np.full(reported, np.nan)
    values[: nominal.n_joints] = nominal.static_moments_kgm
    for i, name in enumerate(problem.names[:reported]):
        values[i] = nominal.passive.get(name, values[i])
    return PredictedBudget(problem.names[:reported], kept, values)


def _open_names(
    model: PassiveModel, open_models: Sequence[PassiveModel], data: IdentificationData, extras: object
) -> list[tuple[list[ParameterName], bool]]:
    """Each open candidate's parameter names, and a nonlinear ``model``'s shape probe's (flagged ``True``)."""
    with_extras = extras is not None
    others = [(list(problem_names(m, data.n_joints, with_extras)), False) for m in open_models]
    if "nonlinear" in model.terms and "higher" not in model.terms:
        higher = model.with_terms(("higher",))
        others.append((list(problem_names(higher, data.n_joints, with_extras)), True))
    return others


def _union_model(model: PassiveModel, open_models: Sequence[PassiveModel]) -> PassiveModel:
    """The model with every column of ``model``, of ``open_models`` and of ``model``'s shape probe (a nonlinear
    model's next order): each of them is a subset of its columns."""
    terms = {term for other in open_models for term in other.terms}
    if "nonlinear" in model.terms:
        terms.add("higher")
    return model.with_terms(tuple(sorted(terms)))


def _score_covariance(
    data: IdentificationData,
    union: Problem,
    fit: Fit,
    sd_m: np.ndarray,
    zero_cov: np.ndarray,
    noise: NoiseSpec,
    kinematics: KinematicsConfig,
    nominal: NominalArm,
    grid_hz: float,
) -> ScoreCovariance:
    """How the scores ``X^T W dtau`` over ``union``'s columns vary between sessions: the sensor noise (long-run),
    the priors, the marker placement (``sd_m``, (n + 1,) m, per chain point) and the sensor zero (``zero_cov``,
    (6, 6) N and Nm), at the predicted weights ``fit.weights`` of the chosen model's ``fit``."""
    n = data.n_joints
    x = np.stack([union.joint_rows(j)[0] for j in range(n)], axis=1)
    sample = sample_noise(data.q_rad, data.lengths_m, np.asarray(nominal.static_moments_kgm), noise, kinematics)
    design, long_run = information_products(x, union.rows, sample, noise, grid_hz)
    precision = union.prior_precision
    noise_part = long_run + np.diag(precision)
    placement = np.zeros_like(noise_part)
    values = union.prior_mean.copy()
    values[:n] = fit.values[:n]
    if sd_m.any():
        shifted = dataclasses.replace(fit, values=values)
        moved = joint_products(union, fit.weights, offset_columns(data, union, shifted, sd_m))
        placement = moved @ moved.T
    total = noise_part + placement
    unit = offset_torques_nm(data, np.eye(3))
    zero = np.stack([joint_products(union, fit.weights, torques) for torques in unit], axis=1)  # (q, 6)
    total += zero @ zero_cov @ zero.T
    return ScoreCovariance(
        names=list(union.names), design=design + np.diag(precision), noise=noise_part, total=total, placement=placement
    )


def nominal_data(
    trajectory: Trajectory,
    duration_s: float,
    nominal: NominalArm,
    passive: Any,
    noise: NoiseSpec,
    kinematics: KinematicsConfig,
    trunk_tilts_rad: Sequence[float],
    grid_hz: float,
) -> IdentificationData:
    """The samples identify will see of a session that follows ``trajectory``, noise-free, one recording per trunk
    tilt (rad) combined as identify combines them: world angles, the motion's velocities, the nominal arm's gravity
    torques and ``passive`` moments (a :class:`~bsp_ros.core.simulation.PassiveTruth`), the motion's rates (the
    torques quasi-static: the inertial ones are below 1 % of gravity on a plan) and the direction velocities'
    predicted noise (identify's deadband).

    Raises
    ------
    InputError
        A session length or grid rate out of range, or a trajectory whose joints are not the arm's.
    """
    n = nominal.n_joints
    if trajectory.n_joints != n:
        raise InputError(f"the trajectory has {trajectory.n_joints} joints, the arm {n} segments")
    if not 0 < duration_s <= 86_400.0 or not 0 < grid_hz <= noise.wrench_hz:
        raise InputError(f"session length {duration_s:g} s or grid {grid_hz:g} Hz out of range")
    t = np.arange(int(duration_s * grid_hz)) / grid_hz
    q = trajectory.angles_rad(t)
    velocity = trajectory.velocities_rad_s(t)
    acceleration = acceleration_rad_s2(trajectory, t)
    lengths = np.asarray(nominal.lengths_m)
    beta = np.asarray(nominal.static_moments_kgm)
    moments = passive.elastic_nm(q) + passive.friction_nm(velocity)  # they follow the angles to the trunk
    recordings = []
    for k, tilt in enumerate(trunk_tilts_rad):
        world = q.copy()
        world[:, 0] += tilt
        tau = np.einsum("tij,j->ti", gravity_regressor(world), beta) + moments
        start_ns = k * (round(duration_s * 1e9) + _RECORDING_GAP_NS)
        recordings.append(
            IdentificationData(
                t_ns=start_ns + np.round(t * 1e9).astype(np.int64),
                q_rad=world,
                velocity_rad_s=velocity,
                tau_nm=tau,
                lengths_m=lengths,
                lengths_std_m=np.zeros(n),
                velocity_noise_rad_s=sample_noise(world, lengths, beta, noise, kinematics).velocity_noise_rad_s,
                n_wrench_samples=round(t.size * noise.wrench_hz / grid_hz),
                # The motion's rates, as identify measures them: its inertial columns (with their priors) take part
                # in every fit. In a model with nonlinear and coupled elastic terms they tell the static moments
                # from the elastic moments (the richest auto candidate's upper arm: sensor-noise std 0.063 kg m
                # predicted, 0.09 reported; 0.39 predicted without them).
                qd_rad_s=velocity,
                qdd_rad_s2=acceleration,
            )
        )
    return combine_recordings(recordings, [float(tilt) for tilt in trunk_tilts_rad])


def acceleration_rad_s2(trajectory: Trajectory, t_s: np.ndarray) -> np.ndarray:
    """(N, n) the trajectory's joint accelerations at ``t_s`` (N,) s, rad/s^2: central differences of its
    velocities over 1 ms (exact for the planner's piecewise-cubic motion away from its knots)."""
    step_s = 1e-3
    ahead = trajectory.velocities_rad_s(t_s + step_s)
    behind = trajectory.velocities_rad_s(np.clip(t_s - step_s, 0.0, None))
    return np.asarray((ahead - behind) / (t_s + step_s - np.clip(t_s - step_s, 0.0, None))[:, None])


def _noise_terms(
    data: IdentificationData,
    problem: Problem,
    probe: Problem | None,
    nominal: NominalArm,
    noise: NoiseSpec,
    kinematics: KinematicsConfig,
    grid_hz: float,
) -> tuple[Fit, Ledger]:
    """The sensor noise's terms of ``problem`` (with ``probe``, its shape probe's too) and the fit identify would
    make of the nominal samples at the predicted weights (values nominal, design ``A + P``): what the placement
    and zero propagations need of it.

    The grid's samples stand for ``wrench_hz / grid_hz`` wrench samples each: the weights carry that factor, so
    the priors weigh what they weigh against the whole session.
    """
    n = data.n_joints
    columns = problem if probe is None else probe
    # The model's columns first, in its order, then the probe's own.
    order = [columns.names.index(name) for name in problem.names]
    order += [i for i in range(len(columns.names)) if i not in order]
    x = np.stack([columns.joint_rows(j)[0] for j in range(n)], axis=1)[:, :, order]
    beta = np.asarray(nominal.static_moments_kgm)
    sample = sample_noise(data.q_rad, data.lengths_m, beta, noise, kinematics)
    design, long_run = information_products(x, problem.rows, sample, noise, grid_hz)
    precision = columns.prior_precision[order]
    p = len(problem.names)
    fit_covariance, choice = covariance_terms(design, long_run, precision, p)
    ledger = Ledger.of(Term.SENSOR_NOISE, fit_covariance)
    if choice is not None:
        ledger = ledger.plus(Term.MODEL_CHOICE, choice)
    values = problem.prior_mean.copy()
    values[:n] = beta
    weights = noise.wrench_hz / grid_hz * sample.weights
    fit = Fit(
        values=values,
        covariance=fit_covariance,
        residual=np.where(problem.rows, 0.0, np.nan),
        sigma=1.0 / np.sqrt(sample.weights),
        condition=float("nan"),
        lags=0,
        design=design[:p, :p] + np.diag(precision[:p]),
        weights=weights,
    )
    return fit, ledger


def nominal_passive_truth(trajectory: Trajectory, duration_s: float, n: int, *, elastic: bool, nonlinear: bool) -> Any:
    """The nominal arm's passive moments along ``trajectory`` over ``duration_s`` (s), ``n`` joints: the cell's
    Coulomb friction; with ``elastic`` the relaxed arm's springs about the middle of the motion; with ``nonlinear``
    also their stiffening and the two-joint muscle. A :class:`~bsp_ros.core.simulation.PassiveTruth`."""
    from bsp_ros.core.simulation import PassiveTruth

    q = trajectory.angles_rad(np.linspace(0.0, duration_s, 2001))
    springs = elastic or nonlinear
    return PassiveTruth(
        coulomb_nm=NOMINAL_COULOMB_NM[:n],
        stiffness_nm_per_rad=NOMINAL_STIFFNESS_NM_PER_RAD[:n] if springs else (0.0,) * n,
        neutral_rad=tuple(float(v) for v in np.median(q, axis=0)),
        stiffening_nm=NOMINAL_STIFFENING_NM[:n] if nonlinear else (0.0,) * n,
        biarticular_nm=NOMINAL_BIARTICULAR_NM if nonlinear else 0.0,
        biarticular_neutral_rad=float(np.median(q[:, 0] + q[:, 1])),
    )
