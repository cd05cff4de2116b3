"""Predicted parameter covariance of the stacked identification for a trajectory, before the session."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from bsp_ros.core.anthropometry import check_body_mass_kg, check_sex, segment_norm
from bsp_ros.core.identification.elastic import ElasticReference, elastic_columns, elastic_prior_precision
from bsp_ros.core.identification.joint import JointConfig
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.result import ParameterName
from bsp_ros.core.identification.stacked import problem_names
from bsp_ros.core.joint_angles import KinematicsConfig, direction_noise_gain
from bsp_ros.core.model import (
    absolute_angles_rad,
    check_lengths_m,
    contact_jacobian,
    contact_torques_nm,
    gravity_regressor,
    static_moments_kgm,
)
from bsp_ros.core.normalised import normalising
from bsp_ros.core.streams import joints_for, segments_for
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_array, check_finite_scalar, check_positive


class Trajectory(Protocol):
    """What a prediction needs of a joint trajectory (``TrajectorySpec`` and ``PlannedTrajectory`` have it)."""

    @property
    def n_joints(self) -> int:
        """Number of joints (2 or 3)."""
        ...

    def angles_rad(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint angles at ``t_s`` (s since the session start): (N,) -> (N, n) rad."""
        ...

    def velocities_rad_s(self, t_s: npt.ArrayLike) -> np.ndarray:
        """Joint velocities at ``t_s``: (N,) -> (N, n) rad/s."""
        ...


@dataclass(frozen=True)
class NoiseSpec:
    """Sensor noise the prediction assumes (the simulator's defaults).

    Attributes
    ----------
    force_noise_n : white force noise per axis, N (1 sd).
    torque_noise_nm : white moment noise per axis, Nm (1 sd).
    marker_noise_m : white marker position noise per axis, m (1 sd).
    wrench_hz : wrench rate, Hz.
    marker_hz : marker frame rate, Hz.
    """

    force_noise_n: float = 0.05
    torque_noise_nm: float = 0.005
    marker_noise_m: float = 1e-4
    wrench_hz: float = 100.0
    marker_hz: float = 50.0

    def __post_init__(self) -> None:
        check_finite_scalar("force noise (N)", self.force_noise_n, 0.0, 100.0)
        check_finite_scalar("torque noise (Nm)", self.torque_noise_nm, 0.0, 10.0)
        check_finite_scalar("marker noise (m)", self.marker_noise_m, 0.0, 0.1)
        check_positive("wrench rate (Hz)", self.wrench_hz, 5000.0)
        check_positive("marker rate (Hz)", self.marker_hz, 5000.0)
        if self.force_noise_n == 0 and self.torque_noise_nm == 0 and self.marker_noise_m == 0:
            raise InputError("at least one noise level must be positive: a noise-free session has no std to predict")


@normalising
@dataclass(frozen=True)
class NominalArm:
    """The arm a prediction assumes: segment lengths and grouped static moments (and passive values).

    Attributes
    ----------
    lengths_m : (n,) segment lengths, m.
    static_moments_kgm : (n,) grouped static moments, kg m (docs/contract.md).
    passive : parameter name -> nominal value (e.g. ``("offset_nm", "elbow"): 0.2``) for relative stds.
    """

    lengths_m: tuple[float, ...]
    static_moments_kgm: tuple[float, ...]
    passive: dict[ParameterName, float] = field(default_factory=dict)

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: tuples of floats."""
        lengths = check_lengths_m(given.lengths_m)
        moments = check_finite_array("static moments (kg m)", given.static_moments_kgm, (lengths.size,))
        if (moments <= 0).any():
            raise InputError(f"static moments must be positive, got {moments.tolist()}")
        return {"lengths_m": tuple(float(v) for v in lengths), "static_moments_kgm": tuple(float(v) for v in moments)}

    @classmethod
    def from_anthropometry(cls, lengths_m: npt.ArrayLike, sex: str = "male", body_mass_kg: float = 75.0) -> NominalArm:
        """Masses and COMs of the de Leva table (``bsp_ros.core.anthropometry``) for the given segment lengths."""
        lengths = check_lengths_m(lengths_m)
        mass = check_body_mass_kg(body_mass_kg)
        norms = [segment_norm(check_sex(sex), name) for name in segments_for(lengths.size)]
        masses = np.array([norm.mass_fraction * mass for norm in norms])
        com = np.array([norm.com_fraction for norm in norms]) * lengths
        return cls(tuple(lengths), tuple(static_moments_kgm(lengths, masses, com)))

    @property
    def n_joints(self) -> int:
        """Number of joints (= segments)."""
        return len(self.lengths_m)


@dataclass(frozen=True)
class Prediction:
    """Predicted covariance of the stacked identification on one trajectory.

    Attributes
    ----------
    names : (p,) parameter names, in the estimator's order.
    covariance : (p, p) predicted covariance.
    nominal : (p,) nominal values (NaN where none is assumed).
    condition_number : of the column-scaled weighted regressor (the estimator's figure).
    max_corr_with_gravity : per passive parameter ``key/joint``, the largest |correlation| with a static moment.
    rows_used : joint -> samples above the direction deadband (whole session, at the wrench rate).
    """

    names: list[ParameterName]
    covariance: np.ndarray
    nominal: np.ndarray
    condition_number: float
    max_corr_with_gravity: dict[str, float]
    rows_used: dict[str, int]

    @property
    def std(self) -> np.ndarray:
        """(p,) predicted one standard deviation of each parameter."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    def std_of(self, quantity: str, owner: str) -> float:
        """Predicted std of one parameter."""
        return float(self.std[self.names.index((quantity, owner))])

    @property
    def max_relative_static_std(self) -> float:
        """Largest predicted std / nominal value over the static moments."""
        picks = [i for i, (key, _) in enumerate(self.names) if key == "static_moment_kgm"]
        return float(np.max(self.std[picks] / np.abs(self.nominal[picks])))

    def table(self) -> list[dict[str, Any]]:
        """One row per parameter: ``quantity``, ``owner``, ``std``, ``nominal``, ``relative_std``."""
        rows = []
        for (key, owner), sd, value in zip(self.names, self.std, self.nominal, strict=True):
            relative = float(sd / abs(value)) if np.isfinite(value) and value != 0 else None
            nominal = float(value) if np.isfinite(value) else None
            rows.append(
                {"quantity": key, "owner": owner, "std": float(sd), "nominal": nominal, "relative_std": relative}
            )
        return rows


def predicted_model(passive: PassiveModel) -> PassiveModel:
    """The fixed model a prediction is made for: ``--passive auto`` as its richest candidate (every elastic term
    of the family; the std `auto` reports holds the spread across the models the data cannot reject, which the
    richest model's covariance bounds from above where the data cannot reject it)."""
    return passive.candidates()[-1] if passive.select else passive


def parameter_names(n_joints: int, passive: PassiveModel) -> list[ParameterName]:
    """The estimator's parameter order (quasi-static): static moments, each joint's local passive terms, then the
    elastic ones (``identification.stacked.problem_names``)."""
    return problem_names(predicted_model(passive), n_joints, dynamics=False)


def regressor(
    q_rad: np.ndarray, velocity_rad_s: np.ndarray, passive: PassiveModel, passive_q_rad: np.ndarray | None = None
) -> np.ndarray:
    """The stacked regressor the estimator builds (``identification.stacked``): (N, n, p).

    Gravity columns from ``bsp_ros.core.model.gravity_regressor`` on the world angles ``q_rad``, passive columns
    from ``PassiveModel.columns`` and elastic columns (nonlinear, coupling) centred on their range, both on
    ``passive_q_rad`` (the angles to the trunk; default ``q_rad``: an upright trunk).
    """
    model = predicted_model(passive)
    passive_q = q_rad if passive_q_rad is None else passive_q_rad
    n = q_rad.shape[1]
    k = len(model.local)
    out = np.zeros((q_rad.shape[0], n, n + n * k))
    out[:, :, :n] = gravity_regressor(q_rad)
    for j in range(n):
        out[:, j, n + j * k : n + (j + 1) * k] = model.columns(passive_q, velocity_rad_s, j)
    if model.elastic:
        reference = ElasticReference.from_angles(passive_q)
        out = np.concatenate((out, elastic_columns(passive_q, model.elastic, reference)), axis=2)
    return out


def _angle_noise_covariance(q_rad: np.ndarray, lengths: np.ndarray, marker_noise_m: float) -> np.ndarray:
    """(N, n, n) covariance of the raw joint angles from one marker frame's position noise.

    A segment angle moves by the in-plane noise perpendicular to the segment at both of its markers,
    over its length; neighbouring segments share a marker, which correlates them.
    """
    n = lengths.size
    phi = absolute_angles_rad(q_rad)
    cov_phi = np.zeros((q_rad.shape[0], n, n))
    var = marker_noise_m**2
    for j in range(n):
        cov_phi[:, j, j] = 2.0 * var / lengths[j] ** 2
        if j + 1 < n:
            shared = -var * np.cos(phi[:, j + 1] - phi[:, j]) / (lengths[j] * lengths[j + 1])
            cov_phi[:, j, j + 1] = shared
            cov_phi[:, j + 1, j] = shared
    relative = np.eye(n) - np.eye(n, k=-1)  # q1 = phi1, q_j = phi_j - phi_{j-1}
    return np.asarray(relative @ cov_phi @ relative.T)


def _residual_gain(q_rad: np.ndarray, lengths: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """(N, n, n) d(residual)/d(angle error): how an angle error at fixed wrench moves the torque residual.

    The measured torque ``-J(q)^T F`` and the gravity prediction ``Y(q) beta`` both take the noisy angle.
    """
    tau_gravity = np.einsum("nij,j->ni", gravity_regressor(q_rad), beta)
    jacobian = contact_jacobian(q_rad, lengths)
    n = lengths.size
    if n == 3:
        wrench = np.linalg.solve(np.transpose(jacobian, (0, 2, 1)), -tau_gravity[..., None])[..., 0]
    else:  # a two-segment chain transmits no moment: solve for the force alone
        force = np.linalg.solve(np.transpose(jacobian[:, :2, :], (0, 2, 1)), -tau_gravity[..., None])[..., 0]
        wrench = np.column_stack((force, np.zeros(q_rad.shape[0])))
    step = 1e-6
    gain = np.empty((q_rad.shape[0], n, n))
    for k in range(n):
        shift = np.zeros(n)
        shift[k] = step
        plus = contact_torques_nm(q_rad + shift, lengths, wrench) - np.einsum(
            "nij,j->ni", gravity_regressor(q_rad + shift), beta
        )
        minus = contact_torques_nm(q_rad - shift, lengths, wrench) - np.einsum(
            "nij,j->ni", gravity_regressor(q_rad - shift), beta
        )
        gain[:, :, k] = (plus - minus) / (2 * step)
    return gain


# Evaluation grid of a reported prediction, Hz (sums are scaled to the wrench and marker rates).
PREDICTION_GRID_HZ = 10.0


def predict_covariance(
    trajectory: Trajectory,
    duration_s: float,
    nominal: NominalArm,
    passive: PassiveModel,
    noise: NoiseSpec | None = None,
    config: JointConfig | None = None,
    grid_hz: float = PREDICTION_GRID_HZ,
    kinematics: KinematicsConfig | None = None,
    trunk_tilts_rad: Sequence[float] = (0.0,),
) -> Prediction:
    """Predict the covariance the stacked identification (``identify_joint``) will report for a session.

    The force noise maps to per-joint torque noise through ``J^T``; marker noise maps through the angles into
    both the measured torque and the regressor. Wrench noise is white at the wrench rate; the filtered angle
    noise is correlated over the filter's time scale, and its long-run (zero-frequency) variance is that of
    the raw marker noise, so it counts as one independent draw per marker frame, not per wrench sample: the
    effective sample count the estimator's HAC covariance finds. Rows below the estimator's direction
    deadband are left out, as the estimator does.

    Parameters
    ----------
    trajectory : the joint motion.
    duration_s : session length, s.
    nominal : the assumed arm (lengths, static moments) the noise maps through.
    passive : the passive model the estimator will fit.
    noise : sensor noise (default ``NoiseSpec()``).
    config : the estimator's settings (deadband), default ``JointConfig(passive=passive)``.
    grid_hz : evaluation grid, Hz; sums are scaled to the wrench and marker rates.
    kinematics : the angle filters the estimator uses (for the direction-velocity noise).
    trunk_tilts_rad : one recording of ``trajectory`` per trunk posture (rad; the motion relative to the trunk,
        gravity turned by the tilt), identified together (``bsp identify BAG1 BAG2 --trunk-tilt-deg ...``).

    Returns
    -------
    Prediction
    """
    noise = noise or NoiseSpec()
    config = config or JointConfig(passive=passive)
    kinematics = kinematics or KinematicsConfig()
    n = nominal.n_joints
    motion = _motion_on_grid(trajectory, n, duration_s, grid_hz, noise.wrench_hz)
    lengths = np.asarray(nominal.lengths_m)
    beta = np.asarray(nominal.static_moments_kgm)
    tilts = _checked_tilts(trunk_tilts_rad)
    model = predicted_model(passive)
    # A nonlinear model's estimate also carries its shape probe's std (identification.selection.shape_probe):
    # the probe's columns extend the model's, so one pass gives both.
    probe = model.with_terms(("higher",)) if "nonlinear" in model.terms and "higher" not in model.terms else None
    information = _stacked_information(motion, tilts, probe or model, lengths, beta, noise, config, kinematics)
    names = parameter_names(n, passive)
    covariance = _predicted_covariance(information, names, probe, n)
    p = len(names)
    condition = _condition_number(information.design[:p, :p])
    per_wrench = noise.wrench_hz / motion.grid_hz
    rows_used = {joint: round(per_wrench * information.rows_total[j]) for j, joint in enumerate(joints_for(n))}
    max_corr = _max_correlations(covariance, names, n)
    return Prediction(names, covariance, _nominal_values(names, nominal), condition, max_corr, rows_used)


@dataclass(frozen=True, kw_only=True)
class _GridMotion:
    """The trajectory on the prediction's evaluation grid.

    Attributes
    ----------
    q_rad : joint angles relative to the trunk, rad; shape (N, n).
    velocity_rad_s : joint velocities, rad/s; shape (N, n).
    grid_hz : the grid's rate, Hz.
    """

    q_rad: np.ndarray
    velocity_rad_s: np.ndarray
    grid_hz: float


def _motion_on_grid(trajectory: Trajectory, n: int, duration_s: float, grid_hz: float, wrench_hz: float) -> _GridMotion:
    """``trajectory`` sampled at ``grid_hz`` (Hz, at most the wrench rate ``wrench_hz``) over ``duration_s`` (s).

    Raises
    ------
    InputError
        A session length or grid rate out of range, or a trajectory whose joints are not the arm's ``n``.
    """
    duration = check_positive("session length (s)", duration_s, 86_400.0)
    grid = check_positive("evaluation grid (Hz)", grid_hz, wrench_hz)
    if trajectory.n_joints != n:
        raise InputError(f"the trajectory has {trajectory.n_joints} joints, the arm {n} segments")
    t = np.arange(int(duration * grid)) / grid
    return _GridMotion(q_rad=trajectory.angles_rad(t), velocity_rad_s=trajectory.velocities_rad_s(t), grid_hz=grid)


def _checked_tilts(trunk_tilts_rad: Sequence[float]) -> tuple[float, ...]:
    """The trunk tilts as floats, rad.

    Raises
    ------
    InputError
        No tilt, or one beyond 90 deg.
    """
    tilts = tuple(float(tilt) for tilt in trunk_tilts_rad)
    if not tilts or not all(abs(tilt) <= np.pi / 2 for tilt in tilts):
        raise InputError(f"trunk tilts must be one or more within +-90 deg, got {np.degrees(tilts).round(1).tolist()}")
    return tilts


@dataclass(frozen=True, kw_only=True)
class _Information:
    """What the recordings of every posture give together, with the columns of the model they were built for.

    Attributes
    ----------
    design : the weighted information ``X^T W X`` summed over the postures; shape (p, p).
    long_run : the long-run covariance of ``X^T W e`` summed over the postures; shape (p, p).
    rows_total : each joint's grid rows the estimator keeps, summed over the postures; shape (n,).
    """

    design: np.ndarray
    long_run: np.ndarray
    rows_total: np.ndarray


def _stacked_information(
    motion: _GridMotion,
    tilts: tuple[float, ...],
    model: PassiveModel,
    lengths: np.ndarray,
    beta: np.ndarray,
    noise: NoiseSpec,
    config: JointConfig,
    kinematics: KinematicsConfig,
) -> _Information:
    """The information of one recording of ``motion`` per trunk tilt (rad), identified together.

    Parameters
    ----------
    motion : the motion relative to the trunk on the evaluation grid.
    tilts : the trunk's tilt in each recording, rad.
    model : the passive model whose columns the information is of.
    lengths, beta : the arm's segment lengths (m) and static moments (kg m); each of shape (n,).
    noise, config, kinematics : as for :func:`predict_covariance`.
    """
    q, velocity = motion.q_rad, motion.velocity_rad_s
    postures = []
    for tilt in tilts:
        # The same motion relative to the trunk, recorded once per posture: gravity sees the world angles.
        world = q.copy()
        world[:, 0] += tilt
        postures.append(
            _posture_information(world, q, velocity, model, lengths, beta, noise, config, kinematics, motion.grid_hz)
        )
    return _Information(
        design=np.sum([posture[0] for posture in postures], axis=0),
        long_run=np.sum([posture[1] for posture in postures], axis=0),
        rows_total=np.sum([posture[2].sum(axis=0) for posture in postures], axis=0),
    )


def _predicted_covariance(
    information: _Information, names: list[ParameterName], probe: PassiveModel | None, n: int
) -> np.ndarray:
    """The covariance the estimator reports for the parameters ``names`` (p, p), with a shape probe's excess
    variance when the model has one (``probe``, the model with its columns; ``information`` is of its columns)."""
    p = len(names)
    probe_names = None if probe is None else problem_names(probe, n, dynamics=False)
    precision = elastic_prior_precision(names if probe_names is None else probe_names)
    fit, choice = covariance_terms(information.design, information.long_run, precision, p)
    return fit if choice is None else fit + choice


def covariance_terms(
    design: np.ndarray, long_run: np.ndarray, precision: np.ndarray, p: int
) -> tuple[np.ndarray, np.ndarray | None]:
    """The fit's covariance of the first ``p`` parameters (p, p), and the model-choice term a shape probe adds
    (p, p; None without a probe).

    Parameters
    ----------
    design, long_run : ``X^T W X`` and the long-run covariance of ``X^T W e`` (q, q) of the columns the
        information is of: the model's ``p``, then (``q > p``) its shape probe's extra ones.
    precision : (q,) the estimator's Gaussian priors, 1 / sd^2 in each parameter's unit (0: none).
    p : the model's parameter count.
    """
    covariance = sandwich(design[:p, :p], long_run[:p, :p], precision[:p])
    if design.shape[0] == p:
        return covariance, None
    # The estimator adds the probe's std where larger and its shift squared; under the model the shift's
    # expected square is that same excess variance (nested fits, Hausman 1978): twice the excess in all.
    wide = sandwich(design, long_run, precision)[:p, :p]
    return covariance, np.diag(2.0 * np.clip(np.diag(wide) - np.diag(covariance), 0.0, None))


def _condition_number(design: np.ndarray) -> float:
    """The condition number of the column-scaled weighted regressor, from its Gram matrix ``design`` (p, p);
    infinite where a column has no rows."""
    norms = np.sqrt(np.clip(np.diag(design), 0.0, None))
    condition = float("inf")
    if (norms > 0).all() and np.isfinite(design).all():  # a column without rows: nothing to condition
        gram = design / np.outer(norms, norms)
        eigen = np.linalg.eigvalsh(0.5 * (gram + gram.T))
        condition = float(np.sqrt(eigen[-1] / eigen[0])) if eigen[0] > 0 else float("inf")
    return condition


def _max_correlations(covariance: np.ndarray, names: list[ParameterName], n: int) -> dict[str, float]:
    """Per passive parameter ``key/joint``, its largest absolute correlation with one of the ``n`` static moments
    (the first ``n`` of ``names``) under ``covariance`` (p, p)."""
    variances = np.diag(covariance)
    correlation = covariance / np.sqrt(np.outer(variances, variances) + 1e-300)
    return {
        f"{key}/{owner}": float(np.max(np.abs(correlation[i, :n]))) for i, (key, owner) in enumerate(names) if i >= n
    }


def _nominal_values(names: list[ParameterName], nominal: NominalArm) -> np.ndarray:
    """The nominal value of each parameter of ``names`` (p,): the arm's static moments, then its passive values
    where it has them, NaN elsewhere."""
    n = nominal.n_joints
    nominal_values = np.full(len(names), np.nan)
    nominal_values[:n] = np.asarray(nominal.static_moments_kgm)
    for i, name in enumerate(names):
        if name in nominal.passive:
            nominal_values[i] = nominal.passive[name]
    return nominal_values


def sandwich(design: np.ndarray, long_run: np.ndarray, precision: np.ndarray) -> np.ndarray:
    """The estimator's covariance ``(A + P)^-1 (S + P) (A + P)^-1`` (p, p) of information ``design`` (A) and
    ``long_run`` (S), both (p, p): its Gaussian priors ``precision`` (p,) are information it adds
    (pseudo-observations of variance 1 / P)."""
    prior = np.diag(precision)
    matrix = design + prior
    # Inverted with rows and columns scaled, as the estimator's design_inverse does: unscaled, a pseudo-inverse
    # drops a nearly confounded direction of an elastic model and predicts it a variance of 0. The scales are
    # powers of two relative to the largest diagonal: exact in floating point and the same for twice the data,
    # so a prediction scales with the session's length exactly.
    diagonal = np.clip(np.diag(matrix), 0.0, None)
    top = float(diagonal.max()) if diagonal.size and diagonal.max() > 0 else 1.0
    relative = np.where(diagonal > 0, diagonal / top, 1.0)
    scale = np.where(diagonal > 0, 2.0 ** np.round(0.5 * np.log2(relative)), 1.0)
    outer = np.outer(scale, scale)
    inverse = np.linalg.pinv(matrix / outer, hermitian=True) / outer
    covariance = inverse @ (long_run + prior) @ inverse
    return np.asarray(0.5 * (covariance + covariance.T))


@dataclass(frozen=True, kw_only=True)
class SampleNoise:
    """The sensor noise of each sample's joint torques, as the estimator sees it.

    Attributes
    ----------
    force_cov : (N, n, n) torque covariance from the wrench noise (white, per wrench sample), Nm^2.
    marker_cov : (N, n, n) torque covariance from one marker frame's angle noise, Nm^2.
    weights : (n,) the estimator's per-joint weights, 1 / Nm^2 (its residual variance; the filtered angle noise
        keeps ~2 fc / f of it).
    velocity_noise_rad_s : (n,) noise of the direction velocities, rad/s (the direction deadband's scale).
    """

    force_cov: np.ndarray
    marker_cov: np.ndarray
    weights: np.ndarray
    velocity_noise_rad_s: np.ndarray


def sample_noise(
    q: np.ndarray, lengths: np.ndarray, beta: np.ndarray, noise: NoiseSpec, kinematics: KinematicsConfig
) -> SampleNoise:
    """The torque noise of each sample at world angles ``q`` (N, n) rad, for segment ``lengths`` (n,) m and static
    moments ``beta`` (n,) kg m: force noise through ``J^T``, marker noise through the angles."""
    angle_cov = _angle_noise_covariance(q, lengths, noise.marker_noise_m)
    angle_sd = np.sqrt(np.einsum("nii->ni", angle_cov).mean(axis=0))
    velocity_noise = angle_sd * direction_noise_gain(kinematics.direction_cutoff_hz, noise.marker_hz)
    jacobian = contact_jacobian(q, lengths)
    wrench_var = np.array([noise.force_noise_n**2, noise.force_noise_n**2, noise.torque_noise_nm**2])
    force_cov = np.transpose(jacobian, (0, 2, 1)) @ (wrench_var[None, :, None] * jacobian)
    gain = _residual_gain(q, lengths, beta)
    marker_cov = gain @ angle_cov @ np.transpose(gain, (0, 2, 1))
    band = min(2.0 * kinematics.cutoff_hz / noise.marker_hz, 1.0)
    sigma2 = np.einsum("nii->ni", force_cov).mean(axis=0) + band * np.einsum("nii->ni", marker_cov).mean(axis=0)
    return SampleNoise(
        force_cov=force_cov,
        marker_cov=marker_cov,
        weights=1.0 / np.maximum(sigma2, 1e-30),
        velocity_noise_rad_s=velocity_noise,
    )


def information_products(
    x: np.ndarray, rows: np.ndarray, sample: SampleNoise, noise: NoiseSpec, grid: float
) -> tuple[np.ndarray, np.ndarray]:
    """The weighted information ``X^T W X`` (p, p) and the long-run covariance of ``X^T W e`` (p, p) of the
    regressor ``x`` (N, n, p) on its ``rows`` (N, n) bool, for samples on a grid of ``grid`` Hz standing for the
    wrench rate's.

    Wrench noise is white at the wrench rate; the filtered angle noise is correlated over the filter's time
    scale and its long-run variance is the raw marker noise's: one independent draw per marker frame.
    """
    w = np.where(rows, sample.weights[None, :], 0.0)
    wx = x * w[..., None]  # (N, n, p)
    per_wrench = noise.wrench_hz / grid
    p = x.shape[2]
    flat = wx.reshape(-1, p)
    design = per_wrench * (x.reshape(-1, p).T @ flat)
    noise_cov = per_wrench * sample.force_cov + noise.wrench_hz**2 / (noise.marker_hz * grid) * sample.marker_cov
    long_run = flat.T @ (noise_cov @ wx).reshape(-1, p)
    return design, long_run


def _posture_information(
    q: np.ndarray,
    passive_q: np.ndarray,
    velocity: np.ndarray,
    passive: PassiveModel,
    lengths: np.ndarray,
    beta: np.ndarray,
    noise: NoiseSpec,
    config: JointConfig,
    kinematics: KinematicsConfig,
    grid: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One recording's weighted information ``X^T W X`` (p, p), the long-run covariance of ``X^T W e`` (p, p) and
    the rows the estimator keeps (N, n), for world angles ``q`` and passive angles ``passive_q`` on the grid."""
    x = regressor(q, velocity, passive, passive_q)
    sample = sample_noise(q, lengths, beta, noise, kinematics)
    # rows the estimator keeps: above the direction deadband (Coulomb models only)
    speed = np.abs(velocity)
    if "coulomb" in passive.terms:
        deadband = np.maximum(
            config.deadband_fraction * np.percentile(speed, 95, axis=0),
            config.deadband_noise_sd * sample.velocity_noise_rad_s,
        )
        rows = speed > deadband[None, :]
    else:
        rows = np.ones_like(speed, dtype=bool)
    design, long_run = information_products(x, rows, sample, noise, grid)
    return design, long_run, rows
