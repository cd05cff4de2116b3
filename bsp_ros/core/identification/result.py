"""The result of an identification: values, covariance, validity and diagnostics."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from bsp_ros.core.identification.joint.held import HeldModel
    from bsp_ros.core.identification.joint.torque_response import TorqueResponse

# A parameter is named by (quantity key, segment or joint name), e.g. ("static_moment_kgm", "forearm")
# or ("coulomb_nm", "elbow"): the same keys as the estimate JSON of docs/contract.md.
ParameterName = tuple[str, str]


@dataclass
class IdentificationResult:
    """What an identification found, and how far to trust it.

    Attributes
    ----------
    method : ``"joint"`` (ours) or ``"paper"`` (the method paper's sequential procedure).
    names : (p,) parameter names.
    values : (p,) estimates (SI units of each key).
    covariance : (p, p) covariance of the estimates.
    valid : False when the data cannot support the estimate (poor excitation, too few samples, ...).
    message : why not valid, or a one-line summary.
    warnings : plain-language notes (confounding, bounds, removed samples).
    condition_number : of the column-scaled weighted regressor.
    residual_rms_nm : joint -> RMS of the torque residual (Nm).
    n_samples : samples (time instants) used.
    diagnostics : further figures (per-parameter max correlation with gravity terms, HAC lags, ...).
    torque_response : the estimate's first-order change (p,) for a change (N, n) of the measured torques (Nm),
        where the method provides it (a sensor offset's effect without re-running the estimator).
    held : what the model checks chose (the stacked method), for refits of newer samples without them
        (:func:`bsp_ros.core.identification.joint.refit.refit_held`).
    """

    method: str
    names: list[ParameterName]
    values: np.ndarray
    covariance: np.ndarray
    valid: bool
    message: str
    warnings: list[str] = field(default_factory=list)
    condition_number: float = float("nan")
    residual_rms_nm: dict[str, float] = field(default_factory=dict)
    n_samples: int = 0
    diagnostics: dict[str, object] = field(default_factory=dict)
    torque_response: TorqueResponse | None = field(default=None, repr=False, compare=False)
    held: HeldModel | None = field(default=None, repr=False, compare=False)

    @property
    def std(self) -> np.ndarray:
        """(p,) one standard deviation of each estimate."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))

    @property
    def weak(self) -> bool:
        """Valid, but with a warning that qualifies it (confounding, large uncertainty)."""
        return self.valid and any(w.startswith(("confounded", "uncertain", "elastic")) for w in self.warnings)

    def index(self, quantity: str, owner: str) -> int:
        """Position of a parameter in ``names``."""
        return self.names.index((quantity, owner))

    def value(self, quantity: str, owner: str) -> float:
        """Estimate of one parameter."""
        return float(self.values[self.index(quantity, owner)])

    def std_of(self, quantity: str, owner: str) -> float:
        """One standard deviation of one parameter."""
        return float(self.std[self.index(quantity, owner)])

    def block(self, quantity: str) -> tuple[list[str], np.ndarray, np.ndarray]:
        """Owners, values (k,) and covariance (k, k) of every parameter of one quantity."""
        picks = [i for i, (key, _) in enumerate(self.names) if key == quantity]
        owners = [self.names[i][1] for i in picks]
        return owners, self.values[picks], self.covariance[np.ix_(picks, picks)]
