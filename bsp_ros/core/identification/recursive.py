"""Recursive identification sample by sample: weighted RLS with forgetting, frozen without excitation."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg.lapack import dposv

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.passive import TERMS, PassiveModel
from bsp_ros.core.identification.result import IdentificationResult, ParameterName
from bsp_ros.core.methods import Method
from bsp_ros.core.model import FloatVector, gravity_regressor_one
from bsp_ros.core.streams import joints_for, segments_for
from bsp_ros.validation import check_finite_scalar, check_positive


@dataclass(frozen=True)
class RecursiveConfig:
    """Settings of :class:`RecursiveIdentifier`.

    Attributes
    ----------
    passive : passive model (Coulomb by default).
    memory_s : time constant of the exponential forgetting while the arm moves (s): the parameters may
        drift over this horizon.
    initial_std : prior standard deviation of every parameter (a weak ridge toward zero); the bound of
        the covariance, so that it cannot wind up while excitation is poor.
    deadband_fraction : rows slower than this fraction of the joint's recent peak speed are skipped (the
        causal velocity lags, so its sign is wrong just after a turning point).
    sample_correlation : each sample is worth 1/this of an independent one (filtered angles make
        consecutive samples' errors alike); it inflates the measurement variance.
    max_relative_std : valid only once every static moment is known to this relative precision.
    warmup_s : after a (re)start, samples only teach the peak speeds for this long: the deadband needs
        them, and an early wrong-signed sample would otherwise weigh heavily under the large initial gain.
    """

    passive: PassiveModel = field(default_factory=PassiveModel)
    memory_s: float = 300.0
    initial_std: float = 10.0
    deadband_fraction: float = 0.25
    sample_correlation: float = 10.0
    max_relative_std: float = 0.05
    warmup_s: float = 10.0

    def __post_init__(self) -> None:
        check_positive("memory_s", self.memory_s, 1e6)
        check_positive("initial_std", self.initial_std, 100.0)
        check_finite_scalar("deadband_fraction", self.deadband_fraction, 0.0, 0.9)
        check_finite_scalar("sample_correlation", self.sample_correlation, 1.0, 1e4)
        check_positive("max_relative_std", self.max_relative_std, 10.0)
        check_finite_scalar("warmup_s", self.warmup_s, 0.0, 600.0)


class RecursiveIdentifier:
    """Static moments and passive terms updated with every wrench sample.

    Recursive weighted least squares in information form with exponential forgetting (memory
    ``memory_s``), equivalent to a random walk of the parameters. Forgetting runs only while the arm
    moves, so without excitation the information is frozen and the covariance cannot wind up; a weak
    ridge toward zero (``initial_std``) bounds it from the start.
    """

    def __init__(self, n_segments: int, config: RecursiveConfig | None = None) -> None:
        self.config = config or RecursiveConfig()
        self.n = n_segments
        terms = self.config.passive.local
        self.names: list[ParameterName] = [("static_moment_kgm", s) for s in segments_for(n_segments)]
        self.names += [(TERMS[t][0], j) for j in joints_for(n_segments) for t in terms]
        self.lower = np.array([0.0] * n_segments + [TERMS[t][2] for _ in range(n_segments) for t in terms])
        self._ridge = np.eye(len(self.names)) / self.config.initial_std**2
        self.reset()

    def reset(self) -> None:
        """Start over from the prior (a new session or a clock jump)."""
        p = len(self.names)
        self.theta = np.zeros(p)
        self._information = np.zeros((p, p))
        self._weighted_target = np.zeros(p)
        self._noise_var = np.full(self.n, 0.05**2)
        self._peak_speed = [0.0] * self.n
        self._last_t_ns: int | None = None
        self._first_t_ns: int | None = None
        self._directions = np.zeros((self.n, 2), dtype=np.int64)
        self.n_updates = 0

    def update(self, t_ns: int, q_rad: FloatVector, velocity_rad_s: FloatVector, tau_nm: FloatVector) -> bool:
        """Fold in one sample; False if it carried no excitation (the estimate stayed frozen).

        Parameters
        ----------
        t_ns : stamp (ns), increasing.
        q_rad, velocity_rad_s : (n,) joint angles (rad) and direction velocities (rad/s).
        tau_nm : (n,) contact torques (Nm).
        """
        return self.update_many([(t_ns, q_rad, velocity_rad_s, tau_nm)]) > 0

    def update_many(self, samples: Sequence[tuple[int, FloatVector, FloatVector, FloatVector]]) -> int:
        """Fold in samples that arrived together, in stamp order; how many carried excitation.

        As many :meth:`update` calls, but for one solve at the end and the residuals (which track each joint's
        noise) taken against the estimate before them: the live filter releases ~10 wrenches at each joint state,
        and only the estimate after the last is published.

        Parameters
        ----------
        samples : ``(t_ns, q_rad, velocity_rad_s, tau_nm)`` each, as for :meth:`update`.
        """
        # Plain floats for the per-sample bookkeeping: at 1 kHz, numpy's per-call overhead on 3-vectors
        # would cost more than the arithmetic.
        k = len(self.config.passive.local)
        p = len(self.names)
        rows: list[list[float]] = []  # (M, p) rows of the joints that moved, in order
        targets: list[float] = []
        joints: list[int] = []
        forgets: list[float] = []  # per folded sample
        row_sample: list[int] = []  # which folded sample each row belongs to
        for t_ns, q_rad, velocity_rad_s, tau_nm in samples:
            dt_s = 0.0 if self._last_t_ns is None else max((t_ns - self._last_t_ns) / 1e9, 0.0)
            self._last_t_ns = t_ns
            if self._first_t_ns is None:
                self._first_t_ns = t_ns
            q = [float(v) for v in q_rad]
            velocity = [float(v) for v in velocity_rad_s]
            decay = math.exp(-dt_s / 60.0)
            moving = []
            for j in range(self.n):
                speed = abs(velocity[j])
                self._peak_speed[j] = max(self._peak_speed[j] * decay, speed)
                if speed > self.config.deadband_fraction * self._peak_speed[j]:
                    moving.append(j)
            if t_ns - self._first_t_ns < self.config.warmup_s * 1e9 or not moving:
                continue
            forgets.append(math.exp(-dt_s / self.config.memory_s))
            gravity = gravity_regressor_one(q)
            tau = [float(v) for v in tau_nm]
            for j in moving:
                row = [0.0] * p
                row[: self.n] = gravity[j]
                row[self.n + j * k : self.n + (j + 1) * k] = self.config.passive.row_one(q[j], velocity[j])
                rows.append(row)
                targets.append(tau[j])
                joints.append(j)
                row_sample.append(len(forgets) - 1)
                self._directions[j, 0 if velocity[j] > 0 else 1] += 1
        if not forgets:
            return 0
        design = np.array(rows)
        residuals = (np.array(targets) - design @ self.theta).tolist()
        # Per-joint noise tracks the residuals, clipped at 5 sd so a poor start cannot swamp it; each row is
        # weighted by its joint's noise after its own residual, as one update at a time would.
        noise_var = self._noise_var.tolist()
        row_noise_var = []
        for j, residual in zip(joints, residuals, strict=True):
            noise_var[j] = 0.999 * noise_var[j] + 0.001 * min(residual**2, 25.0 * noise_var[j])
            row_noise_var.append(noise_var[j])
        self._noise_var = np.array(noise_var)
        # Forgetting: the information held before a sample decays with that sample and every later one.
        after = np.cumprod(np.array(forgets[::-1]))[::-1]  # product of the forgetting from each sample on
        later = np.append(after[1:], 1.0)  # from the sample after each on
        weighted = design / np.array(row_noise_var)[:, None] * later[np.array(row_sample)][:, None]
        self._information = self._information * after[0] + weighted.T @ design
        self._weighted_target = self._weighted_target * after[0] + weighted.T @ np.array(targets)
        # LAPACK's Cholesky solve directly: the ridge keeps the matrix positive definite, and at this size
        # numpy.linalg.solve's argument handling costs several times the solve itself (it runs per wrench).
        _, solution, info = dposv(self._information + self._ridge, self._weighted_target)
        if info != 0:
            solution = np.linalg.lstsq(self._information + self._ridge, self._weighted_target, rcond=None)[0]
        self.theta = np.maximum(solution, self.lower)
        self.n_updates += len(forgets)
        return len(forgets)

    @property
    def covariance(self) -> np.ndarray:
        """(p, p) covariance, inflated for the correlation between consecutive samples."""
        return np.linalg.inv(self._information + self._ridge) * self.config.sample_correlation

    def result(self) -> IdentificationResult:
        """The current estimate, valid once the static moments are precise and both directions were seen."""
        covariance = self.covariance
        std = np.sqrt(np.clip(np.diag(covariance), 0.0, None))
        problems = []
        beta, beta_std = self.theta[: self.n], std[: self.n]
        if self.n_updates < 100:
            problems.append(Finding(code=FindingCode.TOO_FEW_SAMPLES, values={"updates": self.n_updates}))
        elif (beta_std > self.config.max_relative_std * np.maximum(beta, 1e-6)).any():
            problems.append(Finding(code=FindingCode.NOT_YET_DETERMINED))
        if "coulomb" in self.config.passive.terms and (self._directions.min(axis=1) < 10).any():
            problems.append(Finding(code=FindingCode.ONE_DIRECTION))
        return IdentificationResult(
            method=Method.RECURSIVE,
            names=list(self.names),
            values=self.theta.copy(),
            covariance=covariance,
            findings=tuple(problems),
            summary=f"{self.n_updates} recursive updates",
            residual_rms_nm={j: float(np.sqrt(v)) for j, v in zip(joints_for(self.n), self._noise_var, strict=True)},
            n_samples=self.n_updates,
        )
