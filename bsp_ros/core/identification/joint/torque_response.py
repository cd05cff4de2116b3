"""The estimate's first-order response to a change of the measured torques: the final fit's solve, held."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.core.identification.covariance import design_inverse
from bsp_ros.core.identification.stacked import Fit, Problem, joint_products


@dataclass(frozen=True)
class TorqueResponse:
    """``d(parameters) = (A + P)^-1 X^T W d(tau)`` over the final fit's rows and per-joint weights, with the
    parameters at a bound held there (a small change does not free them): what re-running the estimator on
    torques changed by a little gives, without re-running it (its discrete choices, outliers, friction
    transitions and passive model, are those of the estimate)."""

    problem: Problem  # the final problem: its used rows and columns
    weights: np.ndarray  # (n,) the fit's per-joint weights
    design: np.ndarray  # (p, p) A + P
    free: np.ndarray  # (p,) bool: parameters off their bounds

    @classmethod
    def of(cls, problem: Problem, fit: Fit) -> TorqueResponse:
        """The response of ``fit``, the weighted bounded fit of ``problem``."""
        at_bound = (fit.values <= problem.lower + 1e-12) | (fit.values >= problem.upper - 1e-12)
        return cls(problem, fit.weights, fit.design, ~at_bound)

    def __call__(self, delta_tau_nm: np.ndarray) -> np.ndarray:
        """(p,) parameter change for a torque change ``delta_tau_nm`` (N, n) Nm at the fit's samples."""
        return self.columns(delta_tau_nm[None])[:, 0]

    def columns(self, deltas_tau_nm: np.ndarray) -> np.ndarray:
        """(p, k) parameter changes for ``k`` torque changes ``deltas_tau_nm`` (k, N, n) Nm: one inverse for all."""
        inverse = design_inverse(self.design[np.ix_(self.free, self.free)])
        out = np.zeros((self.free.size, len(deltas_tau_nm)))
        for k, delta in enumerate(deltas_tau_nm):
            out[self.free, k] = inverse @ joint_products(self.problem, self.weights, delta)[self.free]
        return out
