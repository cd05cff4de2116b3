"""Stream timing: the delay of the wrench stream behind the marker stream, estimated from the data and compensated."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import overload

import numpy as np

from bsp_ros.core.contact_point import chain_markers
from bsp_ros.core.estimate_blocks import DelayBlock, DelaySource, TimingBlock
from bsp_ros.core.identification.covariance import hac_covariance
from bsp_ros.core.identification.data import IdentificationData, _clean_wrench, wrench_world_yzx
from bsp_ros.core.identification.joint.placement_covariance import averaged_torques
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.placement import placement_columns
from bsp_ros.core.identification.rate import IDENTIFICATION_MAX_RATE_HZ, block_means
from bsp_ros.core.joint_angles import (
    KinematicsConfig,
    MarkerKinematics,
    kinematics_from_markers,
    resample_kinematics,
    valid_stamps,
)
from bsp_ros.core.model import GRAVITY_M_S2, absolute_angles_rad, contact_torques_nm
from bsp_ros.core.streams import Session, WrenchSeries
from bsp_ros.errors import DataError, InputError
from bsp_ros.validation import check_finite_scalar

__all__ = [
    "MAX_DELAY_S",
    "DelayProblem",
    "FitRss",
    "WrenchDelay",
    "compensate_wrench_delay",
    "delay_problem",
    "estimate_wrench_delay",
    "linear_rss",
    "measured_stamps_ns",
    "parameter_timing",
    "parameter_timing_block",
    "shifted_session",
]

# The profile searches delays in [-MAX_DELAY_S, MAX_DELAY_S] on a grid of GRID_STEP_S: two computers'
# clocks (NTP/PTP-synchronised) and a sensor's low-pass filter stay well inside 0.1 s.
MAX_DELAY_S = 0.1
GRID_STEP_S = 0.02
# A delay is compensated only when it differs from 0 by more than this many standard deviations: at 2 a
# session without any delay would have a spurious one compensated once in 20 (seen on a simulated one).
RESOLVED_SD = 3.0

# ``fit_rss(data) -> float``: a chi-square-like misfit of one candidate delay's samples: the residual sum of
# squares weighted by the inverse noise variance of each joint, with weights and rows fixed across delays
# (a -2 log-likelihood up to a constant), so that its curvature gives the delay's variance.
FitRss = Callable[[IdentificationData], float]


@dataclass(frozen=True)
class WrenchDelay:
    """How late the wrench stamps are against the marker stamps, and what was done about it.

    A positive delay means a wrench stamped ``t`` was measured at ``t - delay`` (transport, another
    computer's clock, a sensor's filter); compensating it shifts the wrench stamps by ``-delay``.

    Attributes
    ----------
    delay_s : the delay applied to the wrench stamps, s (0 when not resolved).
    std_s : its standard deviation, s (0 for a parameter).
    source : ``"estimated"`` (from the data, resolved), ``"parameter"`` (given) or ``"none"`` (not applied).
    estimate_s, estimate_std_s : the profile's minimum and its std, s (NaN when not estimated).
    n_fits : linear fits the profile took.
    warnings : what the caller should report.
    """

    delay_s: float
    std_s: float
    source: str
    estimate_s: float = math.nan
    estimate_std_s: float = math.nan
    n_fits: int = 0
    warnings: list[str] = field(default_factory=list)

    def block(self) -> DelayBlock:
        """This recording's ``quality.timing`` of the estimate."""
        estimated = math.isfinite(self.estimate_s)
        return DelayBlock(
            wrench_delay_s=float(self.delay_s),
            # JSON holds no NaN: a delay that was neither given nor estimated has no std (0, source "none").
            wrench_delay_std_s=float(self.std_s) if math.isfinite(self.std_s) else 0.0,
            source=DelaySource(self.source),
            estimated_delay_s=float(self.estimate_s) if estimated else None,
            estimated_delay_std_s=float(self.estimate_std_s) if estimated else None,
        )

    def quality(self) -> dict[str, object]:
        """``quality.timing`` of the estimate document (the JSON of :meth:`block`)."""
        return self.block().to_json()


@dataclass(frozen=True)
class DelayProblem:
    """What every candidate delay shares, computed once: the angles on the marker grid and the wrench in world.

    Attributes
    ----------
    kinematics : marker angles and direction velocities (zero-phase filtered: no delay of their own).
    t_ns : (N,) wrench stamps, cleaned and in order, ns.
    wrench_yzx : (N, 3) ``[F_y, F_z, M_x]`` in ``world``.
    """

    kinematics: MarkerKinematics
    t_ns: np.ndarray
    wrench_yzx: np.ndarray

    def valid(self, delay_s: float) -> np.ndarray:
        """(N,) which wrench samples have angles at their stamps shifted by ``-delay_s``."""
        return valid_stamps(self.kinematics, measured_stamps_ns(self.t_ns, delay_s))

    def data(self, delay_s: float, keep: np.ndarray | None = None) -> tuple[IdentificationData, np.ndarray]:
        """The identification samples with the wrench stamps shifted by ``-delay_s``.

        Parameters
        ----------
        delay_s : candidate delay, s.
        keep : (N,) bool, the wrench samples to use (None: every one with angles).

        Returns
        -------
        data : samples at the shifted stamps; valid : (N,) which wrench samples have angles there.
        """
        t = measured_stamps_ns(self.t_ns, delay_s)
        q, velocity, valid = resample_kinematics(self.kinematics, t)
        use = valid if keep is None else keep & valid
        k, wrench = self.kinematics, self.wrench_yzx
        if not use.all():
            t, q, velocity, wrench = t[use], q[use], velocity[use], wrench[use]
        tau = contact_torques_nm(q, k.lengths_m, wrench)
        data = IdentificationData(
            t_ns=t,
            q_rad=q,
            velocity_rad_s=velocity,
            tau_nm=tau,
            lengths_m=k.lengths_m,
            lengths_std_m=k.lengths_std_m,
            velocity_noise_rad_s=k.direction_velocity_noise_rad_s,
        )
        return data, valid

    def rows(self, keep: np.ndarray) -> DelayProblem:
        """The problem on the wrench samples ``keep`` (N,) bool only."""
        return self if keep.all() else DelayProblem(self.kinematics, self.t_ns[keep], self.wrench_yzx[keep])


def delay_problem(
    session: Session, kinematics_config: KinematicsConfig | None = None, kinematics: MarkerKinematics | None = None
) -> DelayProblem:
    """Prepare a session for :func:`estimate_wrench_delay` (marker angles once, the wrench in ``world``);
    ``kinematics``: the markers' angles, when already computed."""
    keep, _, _ = _clean_wrench(session.wrench)
    rotation = np.asarray(session.rotation_world_from_sensor, dtype=np.float64)
    if rotation.ndim == 3:
        rotation = rotation[keep]
    wrench = WrenchSeries(
        session.wrench.t_ns[keep], session.wrench.force_n[keep], session.wrench.torque_nm[keep], session.wrench.frame_id
    )
    if kinematics is None:
        kinematics = kinematics_from_markers(chain_markers(session), session.n_segments, kinematics_config)
    t_ns, wrench_yzx, _ = block_means(
        np.asarray(wrench.t_ns, dtype=np.int64), wrench_world_yzx(wrench, rotation), IDENTIFICATION_MAX_RATE_HZ
    )
    return DelayProblem(kinematics, t_ns, wrench_yzx)


@dataclass(frozen=True)
class _JointColumns:
    """The default profile's linear model, joint by joint: joint ``i``'s torque takes the gravity columns (those of
    the segments it carries) and its own passive columns (sign steps), as :mod:`identification.joint` stacks them;
    the zero blocks of the stacked (N, n, p) regressor are never built."""

    columns: list[np.ndarray]  # per joint i (N, n - i + k [+ spring and shape]): what each candidate changes
    indices: list[np.ndarray]  # per joint, where its columns sit among the p parameters
    n_parameters: int
    nuisances: _Nuisances | None  # None: gravity and friction alone
    fixed_indices: list[np.ndarray] | None = None  # per joint, where the nuisances' fixed columns sit

    @classmethod
    def of(
        cls,
        data: IdentificationData,
        passive: PassiveModel,
        nuisances: _Nuisances | None = None,
        *,
        wide: bool = True,
    ) -> _JointColumns:
        """The gravity and passive columns of ``data``, and beside them (``wide``) the nuisances' (``nuisances``:
        those of a reference, which a small shift of the wrench stamps hardly changes; None: ``data``'s own)."""
        n, k = data.n_joints, len(passive.local)
        # Joint i carries the segments j >= i: its row of gravity_regressor, without the zeros before them.
        gravity = GRAVITY_M_S2 * np.cos(absolute_angles_rad(data.q_rad))
        columns, indices = [], []
        for i in range(n):
            columns.append(np.hstack((gravity[:, i:], passive.columns(data.passive_q_rad, data.velocity_rad_s, i))))
            indices.append(np.concatenate((np.arange(i, n), n + i * k + np.arange(k))))
        p = n + n * k
        narrow = cls(columns, indices, p, None)
        if not wide:
            return narrow
        nuisances = nuisances or _Nuisances.of(data, narrow)
        m = nuisances.n_offsets
        wide_columns, wide_indices, fixed_indices = [], [], []
        k_shape = len(TRANSITION_WIDTHS_RAD_S)
        for i in range(n):
            spring = np.column_stack((np.ones(data.t_ns.size), data.passive_q_rad[:, i]))
            shape = transition_columns(data.velocity_rad_s[:, i])
            wide_columns.append(np.hstack((columns[i], spring, shape)))
            wide_indices.append(
                np.concatenate(
                    (
                        indices[i],
                        p + n + m + 2 * i + np.arange(2),
                        p + n + m + 2 * n + k_shape * i + np.arange(k_shape),
                    )
                )
            )
            fixed_indices.append(np.concatenate((p + np.arange(i, n), p + n + np.arange(m))))
        return cls(wide_columns, wide_indices, p + n + m + (2 + k_shape) * n, nuisances, fixed_indices)

    def _fixed_blocks(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per joint its nuisance columns that do not depend on the candidate delay (N, c) and where they sit among
        the parameters; empty without nuisances."""
        if self.nuisances is None or self.fixed_indices is None:
            return []
        return list(zip(self.nuisances.fixed, self.fixed_indices, strict=True))

    def predicted(self, values: np.ndarray) -> np.ndarray:
        """(N, n) the model's torques at ``values``."""
        out = [x @ values[index] for x, index in zip(self.columns, self.indices, strict=True)]
        for i, (fixed, index) in enumerate(self._fixed_blocks()):
            out[i] = out[i] + fixed @ values[index]
        return np.stack(out, axis=1)

    def fixed_design(self, w: np.ndarray) -> list[np.ndarray]:
        """Per joint ``B^T W B`` of its fixed nuisance columns ``B`` at row weights ``w`` (N, n) (empty without
        nuisances): the same for every candidate of a profile (its rows and weights are the reference's), so a
        profile computes it once."""
        return [(fixed * w[:, i, None]).T @ fixed for i, (fixed, _) in enumerate(self._fixed_blocks())]

    def products(
        self, w: np.ndarray, y: np.ndarray, fixed_design: list[np.ndarray] | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """``X^T W X`` (p, p) and ``X^T W y`` (p,) over the joints' rows: row weights ``w`` (N, n), targets ``y``
        (N, n); ``fixed_design``: :meth:`fixed_design` at ``w``, when already computed."""
        design, moment = np.zeros((self.n_parameters, self.n_parameters)), np.zeros(self.n_parameters)
        weighted = [x * w[:, i, None] for i, x in enumerate(self.columns)]
        for i, (x, index) in enumerate(zip(self.columns, self.indices, strict=True)):
            design[np.ix_(index, index)] += weighted[i].T @ x
            moment[index] += weighted[i].T @ y[:, i]
        blocks = self._fixed_blocks()
        if blocks and fixed_design is None:
            fixed_design = self.fixed_design(w)
        for i, (fixed, other) in enumerate(blocks):
            assert fixed_design is not None  # computed above where there are blocks
            index = self.indices[i]
            cross = weighted[i].T @ fixed
            design[np.ix_(index, other)] += cross
            design[np.ix_(other, index)] += cross.T
            design[np.ix_(other, other)] += fixed_design[i]
            moment[other] += fixed.T @ (w[:, i] * y[:, i])
        return design, moment


# Friction that changes direction over a few mrad/s (a tanh of that width) instead of at once: in the wide profile
# a column per joint and width, ``tanh(v / w) - sign(v)``, takes up the shape. A smooth transition is odd in
# the velocity; a delayed step is not (it falls on the side of the acceleration), so they stay apart. Without them a
# tanh friction of 5 mrad/s on the paper's sines read as a delay of -89 +- 18 ms that both profiles resolved alike
# (with the two narrower widths alone, +5 to +8 ms at 2-3 std).
TRANSITION_WIDTHS_RAD_S = (0.002, 0.008, 0.03)


def transition_columns(velocity_rad_s: np.ndarray) -> np.ndarray:
    """(N, k) the friction transition's shape columns of one joint's direction velocity ``velocity_rad_s`` (N,),
    rad/s: ``tanh(v / w) - sign(v)`` for each width of :data:`TRANSITION_WIDTHS_RAD_S`."""
    v = np.asarray(velocity_rad_s, dtype=np.float64)[:, None]
    widths = np.asarray(TRANSITION_WIDTHS_RAD_S)[None, :]
    return np.asarray(np.tanh(v / widths) - np.sign(v))


@dataclass(frozen=True)
class _Nuisances:
    """What skin markers off their joint centres and a centre of mass off its segment's axis do to the torques, fitted
    beside gravity and friction at every candidate delay: left out, a few mm of marker placement read as tens of ms
    of delay (a delay applied in 30 of 32 sessions of 2 mm placement, in none with them; placement_sharpness.py).

    Attributes
    ----------
    fixed : per joint i the columns it takes, (N, n - i + m): the perpendicular moments' columns ``-g sin`` of the
        absolute angles of the segments it carries, then the m markers' offsets' columns at the static moments of an
        unweighted first fit.
    n_offsets : m.
    """

    fixed: tuple[np.ndarray, ...]
    n_offsets: int

    @classmethod
    def of(cls, data: IdentificationData, narrow: _JointColumns) -> _Nuisances:
        """The nuisances of ``data``, at the static moments of the unweighted fit of its gravity and passive
        columns ``narrow``."""
        n = data.n_joints
        design, moment = narrow.products(np.ones(data.tau_nm.shape), data.tau_nm)
        static = np.linalg.lstsq(design, moment, rcond=None)[0][:n]
        zeros = np.zeros_like(data.q_rad)
        base_values = np.concatenate((static, np.zeros(2 * n)))
        offsets = placement_columns(data.q_rad, zeros, zeros, data.lengths_m, averaged_torques(data), base_values)
        sin = -GRAVITY_M_S2 * np.sin(absolute_angles_rad(data.q_rad))
        return cls(tuple(np.hstack((sin[:, i:], offsets[:, i, :])) for i in range(n)), offsets.shape[2])


@dataclass(frozen=True)
class _LinearFit:
    """The weighted linear model of the default profile, with its rows and weights fixed at a reference."""

    passive: PassiveModel
    rows: np.ndarray  # (N, n) rows used (direction of motion clear at the reference)
    weights: np.ndarray  # (n,) 1 / sigma^2 per joint
    nuisances: _Nuisances | None = None  # the reference's, shared by every candidate
    wide: bool = True  # the nuisances fitted beside gravity and friction
    fixed_design: list[np.ndarray] | None = None  # the nuisances' own products at these rows and weights

    def solve(self, data: IdentificationData, columns: _JointColumns | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Parameters (p,) and residuals (N, n) (0 off the rows) of one candidate (``columns``: its model's, when
        already built)."""
        columns = columns or _JointColumns.of(data, self.passive, self.nuisances, wide=self.wide)
        # Normal equations: a p x p solve (the columns are few and well scaled); lstsq's SVD of the tall
        # matrix would cost 10 times more for each candidate delay.
        weights = np.where(self.rows, self.weights[None, :], 0.0)
        design, moment = columns.products(weights, data.tau_nm, self.fixed_design)
        values = np.linalg.lstsq(design, moment, rcond=None)[0]
        residual = np.where(self.rows, data.tau_nm - columns.predicted(values), 0.0)
        return values, residual

    def rss(self, data: IdentificationData) -> float:
        _, residual = self.solve(data)
        return float((self.weights[None, :] * residual**2).sum())


def _linear_fit(
    reference: IdentificationData, passive: PassiveModel, columns: _JointColumns | None = None, wide: bool = True
) -> _LinearFit:
    speed = np.abs(reference.velocity_rad_s)
    rows = np.ones_like(speed, dtype=bool)
    if "coulomb" in passive.terms:
        # Rows near a reversal would switch their friction sign as the delay moves: left out, as the
        # identification's dead band leaves them out.
        noise = np.nan_to_num(reference.velocity_noise_rad_s, nan=0.0)
        deadband = np.maximum(0.1 * np.percentile(speed, 95, axis=0), 4.0 * noise)
        rows = speed > deadband[None, :]
    columns = columns or _JointColumns.of(reference, passive, wide=wide)
    fit = _LinearFit(passive, rows, np.ones(reference.n_joints), columns.nuisances, wide)
    _, residual = fit.solve(reference, columns)
    sigma = np.sqrt((residual**2).sum(axis=0) / np.maximum(rows.sum(axis=0), 1))
    sigma = np.maximum(sigma, 1e-9 * max(float(np.abs(reference.tau_nm).max()), 1e-9))
    weights = 1.0 / sigma**2
    # The nuisances' columns are the reference's at every candidate, and so are the rows and weights: their own
    # products are computed once for the profile.
    fixed_design = columns.fixed_design(np.where(rows, weights[None, :], 0.0))
    return dataclasses.replace(fit, weights=weights, fixed_design=fixed_design)


def linear_rss(reference: IdentificationData, passive: PassiveModel | None = None, wide: bool = True) -> FitRss:
    """The default ``fit_rss``: the stacked linear model of ``identify_joint`` (static moments and the passive
    terms as sign steps), weighted per joint by its residual variance at ``reference``, rows fixed there.

    Parameters
    ----------
    reference : the samples at the starting delay (0); every candidate must hold the same samples.
    passive : the passive model (Coulomb by default).
    wide : fit the nuisances (off-axis moments, marker offsets, a linear spring) beside gravity and friction.
    """
    return _linear_fit(reference, passive or PassiveModel(), wide=wide).rss


def _parabola(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Vertex and second derivative of the parabola through three points."""
    a, b, _ = np.polyfit(x, y, 2)
    if a <= 0:
        return math.nan, 2.0 * float(a)
    return float(-b / (2.0 * a)), 2.0 * float(a)


def _autocorrelation_inflation(
    minus: IdentificationData,
    centre: IdentificationData,
    plus: IdentificationData,
    h: float,
    passive: PassiveModel,
    wide: bool = True,
    nuisances: _Nuisances | None = None,
) -> float:
    """How much correlated errors widen the delay's std beyond the curvature's (>= 1), from the samples at a delay
    (``centre``) and at ``h`` s either side of it (``minus``, ``plus``); ``nuisances``: the profile's (those of its
    reference, as every candidate of the profile takes them), None: ``centre``'s own.

    The delay's score per sample (summed over the joints), with the model's parameters partialled out,
    goes through the same Newey-West sandwich as the parameters' (``identify_joint``); its std over the
    curvature's ``1 / sqrt(information)`` is the inflation.
    """
    columns = _JointColumns.of(centre, passive, nuisances, wide=wide)
    fit = _linear_fit(centre, passive, columns, wide)
    values, residual = fit.solve(centre, columns)
    if plus.t_ns.size != centre.t_ns.size or minus.t_ns.size != centre.t_ns.size:
        return 1.0
    predicted = lambda d: d.tau_nm - _JointColumns.of(d, passive, columns.nuisances, wide=wide).predicted(values)  # noqa: E731
    slope = (predicted(plus) - predicted(minus)) / (2.0 * h)  # d(residual)/d(delay), (N, n)
    w = np.where(fit.rows, fit.weights[None, :], 0.0)
    # Partial the parameters out: the part of the slope the model's columns cannot take up.
    design, cross = columns.products(w, slope, fit.fixed_design)
    slope = slope - columns.predicted(np.linalg.lstsq(design, cross, rcond=None)[0])
    information = float((w * slope**2).sum())
    scores = (w * slope * residual).sum(axis=1)[:, None]
    if information <= 0:
        return 1.0
    hac, _ = hac_covariance(np.array([[information]]), scores)
    # The curvature's variance is 1 / information (independent errors, at every joint alike); the sandwich's
    # also holds the correlation of one sample's errors across the joints (one wrench error reaches all of
    # them through J^T) and along time.
    return max(1.0, float(np.sqrt(hac[0, 0] * information)))


def _descend(grid: np.ndarray, misfit: Callable[[float], float]) -> np.ndarray:
    """``misfit`` on ``grid`` (NaN where not evaluated), walked downhill from the candidate nearest 0 until a
    minimum is bracketed or an end is reached.

    Over the searched +-0.1 s the misfit of an arm moving at periods of seconds has one minimum, so the walk
    finds the grid's minimum and its two neighbours with the same values as the whole grid, in 3-6 fits of 11.
    """
    values = np.full(grid.size, np.nan)

    def at(k: int) -> float:
        if np.isnan(values[k]):
            values[k] = misfit(float(grid[k]))
        return float(values[k])

    k = int(np.argmin(np.abs(grid)))
    for _ in range(grid.size):  # each step moves one way downhill: at most the whole grid
        here = at(k)
        left = at(k - 1) if k > 0 else np.inf
        right = at(k + 1) if k < grid.size - 1 else np.inf
        if not (left < here or right < here):
            break
        k = k - 1 if left < right else k + 1
    return values


def estimate_wrench_delay(
    session_or_problem: Session | DelayProblem,
    fit_rss: Callable[[IdentificationData], float] | None = None,
    *,
    passive: PassiveModel | None = None,
    kinematics_config: KinematicsConfig | None = None,
    max_delay_s: float = MAX_DELAY_S,
    step_s: float = GRID_STEP_S,
    resolved_sd: float = RESOLVED_SD,
) -> WrenchDelay:
    """Estimate the delay of the wrench stamps behind the marker stamps by a profile over candidate delays.

    For each candidate ``d`` on a grid over ``[-max_delay_s, max_delay_s]``, the wrench stamps are shifted
    by ``-d``, the angles resampled onto them and the model fitted; ``fit_rss`` gives the misfit. A
    parabola through the grid's minimum and its neighbours, refined once around its vertex, gives the
    delay and, from its curvature, the std (widened by the residuals' autocorrelation, judged on the
    linear model). The same wrench samples enter every candidate (those with angles at every shift).

    Parameters
    ----------
    session_or_problem : a session, or its :func:`delay_problem` (to share the marker angles).
    fit_rss : ``fit_rss(data) -> float``, a chi-square-like misfit (see :data:`FitRss`); None: the linear
        model of ``identify_joint`` (:func:`linear_rss`) with rows and weights fixed at delay 0.
    passive : the passive model of the default fit.
    kinematics_config : marker filtering, when a session is given.
    max_delay_s, step_s : the grid, s.
    resolved_sd : the delay is applied (``source`` ``"estimated"``) only when ``|d| > resolved_sd * std``.

    Returns
    -------
    WrenchDelay
        ``delay_s`` the delay to apply (0 when not resolved, ``source`` ``"none"``) and the estimate itself.

    Raises
    ------
    DataError
        Too few wrench samples have angles at every candidate delay.
    """
    check_finite_scalar("max_delay_s", max_delay_s, 1e-3, 10.0)
    check_finite_scalar("step_s", step_s, 1e-4, max_delay_s)
    problem = session_or_problem
    if not isinstance(problem, DelayProblem):
        problem = delay_problem(problem, kinematics_config)
    kept = _rows_at_every_delay(problem, max_delay_s + step_s)
    passive = passive or PassiveModel()
    narrow = _profile_delay(_DelayProfile(kept, fit_rss, passive), max_delay_s, step_s, resolved_sd)
    if fit_rss is not None:
        return narrow  # a caller's own misfit: its model is the one it means
    wide = _profile_delay(_DelayProfile(kept, None, passive, wide=True), max_delay_s, step_s, resolved_sd)
    return _agreed(narrow, wide, resolved_sd)


def _agreed(narrow: WrenchDelay, wide: WrenchDelay, resolved_sd: float) -> WrenchDelay:
    """The delay both profiles resolve alike, else none: the one of gravity and friction alone (``narrow``) and the
    one that also fits off-axis moments, marker offsets and a linear spring (``wide``).

    Each model alone can resolve a delay that is not there: the narrow one from a few mm of marker placement (tens
    of ms in 30 of 32 sessions of 2 mm placement, bench/placement_sharpness.py), the wide one on a short session,
    where its extra columns leave the delay little to stand on (-49 +- 9 ms on 20 s). A delay the data show holds in
    both; where they disagree the data cannot tell it, and it is not compensated. The estimate reported is the wide
    profile's, its std the wider of the two.
    """
    n_fits = narrow.n_fits + wide.n_fits
    warnings = list(dict.fromkeys([*narrow.warnings, *wide.warnings]))
    if wide.source != "estimated":
        return dataclasses.replace(wide, n_fits=n_fits, warnings=warnings)
    std = max(wide.std_s, narrow.std_s) if math.isfinite(narrow.std_s) else wide.std_s
    disagree = not math.isfinite(narrow.estimate_s) or abs(narrow.estimate_s - wide.estimate_s) > 2.0 * math.hypot(
        narrow.std_s if math.isfinite(narrow.std_s) else 0.0, wide.std_s
    )
    if narrow.source != "estimated" or disagree:
        warnings.append(
            f"the wrench-marker delay the data suggest depends on the model ({1e3 * wide.estimate_s:+.3g} ms with "
            f"marker offsets and springs fitted, {1e3 * narrow.estimate_s:+.3g} ms without): not compensated; give it "
            "with --wrench-delay-s if the cell knows it"
        )
        return WrenchDelay(0.0, std, "none", wide.estimate_s, std, n_fits, warnings)
    return WrenchDelay(wide.delay_s, std, "estimated", wide.estimate_s, std, n_fits, warnings)


def _profile_delay(profile: _DelayProfile, max_delay_s: float, step_s: float, resolved_sd: float) -> WrenchDelay:
    """The delay at ``profile``'s minimum over the grid ``[-max_delay_s, max_delay_s]`` in ``step_s``, s."""
    grid = np.arange(-max_delay_s, max_delay_s + 0.5 * step_s, step_s)
    values = _descend(grid, profile.misfit)
    best = int(np.nanargmin(values))
    if best in (0, grid.size - 1):
        return WrenchDelay(
            0.0,
            math.nan,
            "none",
            n_fits=profile.n_fits,
            warnings=[
                f"the wrench-marker delay lies at or beyond the searched +-{max_delay_s:g} s (the misfit falls toward "
                f"{grid[best]:+.3g} s): not compensated; give it with --wrench-delay-s if the cell knows it"
            ],
        )
    return _delay_at_minimum(profile, grid[best - 1 : best + 2], values[best - 1 : best + 2], step_s, resolved_sd)


def _rows_at_every_delay(problem: DelayProblem, reach_s: float) -> DelayProblem:
    """``problem`` on the wrench samples that have angles at every shift within ``reach_s`` (s) either way.

    Raises
    ------
    DataError
        Fewer than 50 such samples.
    """
    # The samples that have angles at every shift the search may try (the refinement stays inside the grid).
    keep = problem.valid(-reach_s) & problem.valid(reach_s) & problem.valid(0.0)
    if keep.sum() < 50:
        raise DataError(
            f"only {int(keep.sum())} wrench samples have joint angles at every delay within +-{reach_s:g} s"
        )
    return problem.rows(keep)  # every candidate's samples are among these: selected once


class _DelayProfile:
    """The misfit of each candidate delay on the same wrench samples, counting the fits it takes.

    Each candidate's samples are built once: the fit's reference (0), the profile and the inflation's slope share
    them (keyed by the shift in whole ns, as applied: the grid's 0 is 0 only to a float's rounding).

    Parameters
    ----------
    kept : the problem on the samples every candidate holds (:func:`_rows_at_every_delay`).
    fit_rss : the misfit (:data:`FitRss`); None: :func:`linear_rss` at delay 0 with ``passive``.
    passive : the passive model of the default fit and of the std's inflation.
    """

    def __init__(self, kept: DelayProblem, fit_rss: FitRss | None, passive: PassiveModel, wide: bool = False) -> None:
        self.kept: DelayProblem = kept
        self.passive: PassiveModel = passive
        self.wide: bool = wide
        self.n_fits: int = 0
        self._samples: dict[int, IdentificationData] = {}
        # The default misfit's nuisance columns are its reference's; the std's inflation takes the same ones.
        self.nuisances: _Nuisances | None = None
        if fit_rss is None:
            fit = _linear_fit(self.samples(0.0), passive, wide=wide)
            fit_rss, self.nuisances = fit.rss, fit.nuisances
        self.rss: FitRss = fit_rss

    def samples(self, delay_s: float) -> IdentificationData:
        """The identification samples with the wrench stamps shifted by ``-delay_s`` (s)."""
        shift_ns = round(delay_s * 1e9)
        if shift_ns not in self._samples:
            self._samples[shift_ns] = self.kept.data(delay_s)[0]
        return self._samples[shift_ns]

    def misfit(self, delay_s: float) -> float:
        """The misfit at ``delay_s`` (s), one fit more."""
        self.n_fits += 1
        return float(self.rss(self.samples(delay_s)))


def _delay_at_minimum(
    profile: _DelayProfile, x: np.ndarray, y: np.ndarray, step_s: float, resolved_sd: float
) -> WrenchDelay:
    """The delay from a parabola through the profile's grid minimum and its neighbours, refined once around its
    vertex, and its std from the curvature widened by the residuals' autocorrelation.

    Parameters
    ----------
    profile : the profile the grid was walked with.
    x, y : the grid's minimum and its two neighbours, s, and their misfits; each of shape (3,).
    step_s : the grid's step, s.
    resolved_sd : the delay is applied only when ``|d| > resolved_sd * std``.
    """
    vertex, curvature = _parabola(x, y)
    if not math.isfinite(vertex):
        return WrenchDelay(
            0.0, math.nan, "none", n_fits=profile.n_fits, warnings=["the wrench-marker delay is not identifiable"]
        )
    # Refine on a narrower parabola around the first vertex: the misfit is quadratic only near its minimum.
    h = 0.25 * step_s
    around = [vertex - h, vertex, vertex + h]
    refined, refined_curvature = _parabola(np.array(around), np.array([profile.misfit(d) for d in around]))
    # The slope of the residuals for the std's inflation: on the refinement's samples (the first vertex and h
    # either side), which the misfit's curvature comes from too.
    minus, centre, plus = (profile.samples(d) for d in around)
    if math.isfinite(refined) and abs(refined - vertex) <= step_s:
        vertex, curvature = refined, refined_curvature
    if not curvature > 0:
        return WrenchDelay(
            0.0, math.nan, "none", n_fits=profile.n_fits, warnings=["the wrench-marker delay is not identifiable"]
        )
    inflation = _autocorrelation_inflation(minus, centre, plus, h, profile.passive, profile.wide, profile.nuisances)
    std = math.sqrt(2.0 / curvature) * inflation
    n_fits = profile.n_fits + 4
    if abs(vertex) > resolved_sd * std:
        return WrenchDelay(vertex, std, "estimated", vertex, std, n_fits)
    return WrenchDelay(0.0, std, "none", vertex, std, n_fits)


@overload
def measured_stamps_ns(t_ns: int, wrench_delay_s: float) -> int: ...
@overload
def measured_stamps_ns(t_ns: np.ndarray, wrench_delay_s: float) -> np.ndarray: ...
def measured_stamps_ns(t_ns: int | np.ndarray, wrench_delay_s: float) -> int | np.ndarray:
    """When wrenches stamped ``t_ns`` were measured, on the markers' clock: ``t_ns - wrench_delay_s``, ns.

    The one place a wrench delay is applied: offline to a session's stamps (:func:`shifted_session`, the delay the
    cell knows or the estimated one) and live to each wrench as it arrives (``bsp_ros.live.online.wrench_input``).
    A positive delay means a wrench stamped ``t`` was measured at ``t - delay``.

    Parameters
    ----------
    t_ns : a wrench stamp (int) or stamps (int64 array), ns.
    wrench_delay_s : the delay, s (rounded to the nanosecond).
    """
    shift_ns = round(wrench_delay_s * 1e9)
    if isinstance(t_ns, np.ndarray):
        return t_ns - np.int64(shift_ns)
    return int(t_ns) - shift_ns


def shifted_session(session: Session, delay_s: float) -> Session:
    """``session`` with its wrench stamps shifted by ``-delay_s`` (a wrench stamped ``t`` was measured at ``t - d``)."""
    if delay_s == 0.0:
        return session
    wrench = dataclasses.replace(session.wrench, t_ns=measured_stamps_ns(session.wrench.t_ns, delay_s))
    return dataclasses.replace(session, wrench=wrench)


def compensate_wrench_delay(
    session: Session,
    wrench_delay_s: float | None,
    kinematics_config: KinematicsConfig | None = None,
    passive: PassiveModel | None = None,
    fit_rss: Callable[[IdentificationData], float] | None = None,
    kinematics: MarkerKinematics | None = None,
) -> tuple[Session, WrenchDelay]:
    """The session with its wrench delay compensated, and what was done.

    Parameters
    ----------
    session : the streams.
    wrench_delay_s : a delay the cell knows (s, ``source`` ``"parameter"``), or None to estimate it
        (:func:`estimate_wrench_delay`), applied only when resolved.
    kinematics_config, passive, fit_rss : as for :func:`estimate_wrench_delay`.
    kinematics : the session markers' angles, when already computed.

    Raises
    ------
    InputError
        ``wrench_delay_s`` is not finite or beyond 10 s.
    """
    if wrench_delay_s is not None:
        check_finite_scalar("wrench_delay_s", wrench_delay_s, -10.0, 10.0)
        return shifted_session(session, wrench_delay_s), WrenchDelay(float(wrench_delay_s), 0.0, "parameter")
    try:
        problem = delay_problem(session, kinematics_config, kinematics)
        delay = estimate_wrench_delay(problem, fit_rss, passive=passive)
    except (DataError, InputError, np.linalg.LinAlgError) as error:
        # The identification itself reports what is wrong with such a session; timing just stays uncompensated.
        return session, WrenchDelay(
            0.0, math.nan, "none", warnings=[f"the wrench-marker delay was not estimated: {error}"]
        )
    return shifted_session(session, delay.delay_s), delay


def parameter_timing(wrench_delay_s: float | None) -> dict[str, object]:
    """The JSON of :func:`parameter_timing_block`."""
    return parameter_timing_block(wrench_delay_s).to_json()


def parameter_timing_block(wrench_delay_s: float | None) -> TimingBlock:
    """``quality.timing`` where the delay is not estimated (live, which cannot estimate it per update): the
    parameter's, ``"none"`` when 0 or unset (live applies 0 then)."""
    if not wrench_delay_s:
        return TimingBlock(recordings=(WrenchDelay(0.0, 0.0, "none").block(),))
    return TimingBlock(recordings=(WrenchDelay(float(wrench_delay_s), 0.0, "parameter").block(),))
