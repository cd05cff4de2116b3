"""The result of an identification: values, covariance, validity and diagnostics."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from bsp_ros.core.findings import Finding, Severity, invalid_texts, note_texts
from bsp_ros.core.identification.ledger import Ledger, Term
from bsp_ros.core.methods import Method

if TYPE_CHECKING:
    from bsp_ros.core.identification.joint.held import HeldModel
    from bsp_ros.core.identification.joint.torque_response import TorqueResponse

# A parameter is named by (quantity key, segment or joint name), e.g. ("static_moment_kgm", "forearm")
# or ("coulomb_nm", "elbow"): the same keys as the estimate JSON of docs/contract.md.
ParameterName = tuple[str, str]


@dataclass(frozen=True, kw_only=True)
class IdentificationResult:
    """What an identification found, and how far to trust it.

    Its verdict is its findings: ``valid``, ``weak``, ``message`` and ``warnings`` are derived from them.

    Attributes
    ----------
    method : the stacked fit of every joint (``joint``, ours), the method paper's sequential procedure
        (``paper``) or the live per-sample filter (``recursive``).
    names : (p,) parameter names.
    values : (p,) estimates (SI units of each key).
    covariance : (p, p) covariance of the estimates.
    findings : what the identification found, in order: an invalid one makes the estimate invalid.
    summary : the one-line summary of a valid estimate (``identified from 4000 samples``).
    ledger : ``covariance`` as a sum of named terms (its uncertainty budget), or None where the method keeps none.
    condition_number : of the column-scaled weighted regressor.
    residual_rms_nm : joint -> RMS of the torque residual (Nm).
    n_samples : samples (time instants) used.
    diagnostics : further figures (per-parameter max correlation with gravity terms, HAC lags, ...).
    torque_response : the estimate's first-order change (p,) for a change (N, n) of the measured torques (Nm),
        where the method provides it (a sensor offset's effect without re-running the estimator).
    held : what the model checks chose (the stacked method), for refits of newer samples without them
        (:func:`bsp_ros.core.identification.joint.refit.refit_held`).
    """

    method: Method
    names: list[ParameterName]
    values: np.ndarray
    covariance: np.ndarray
    findings: tuple[Finding, ...] = ()
    summary: str = ""
    ledger: Ledger | None = None
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
    def n_joints(self) -> int:
        """Joints of the chain: one static moment per segment."""
        return sum(1 for key, _ in self.names if key == "static_moment_kgm")

    @property
    def valid(self) -> bool:
        """Whether the data support the estimate: no finding makes it invalid."""
        return not any(f.severity is Severity.INVALID for f in self.findings)

    @property
    def weak(self) -> bool:
        """Valid, but with a finding that qualifies it (confounding, large uncertainty, a data-chosen model)."""
        return self.valid and any(f.severity is Severity.WEAK for f in self.findings)

    @property
    def message(self) -> str:
        """Why the estimate is not valid (the invalid findings' texts), or its one-line summary."""
        return "; ".join(invalid_texts(self.findings)) or self.summary

    @property
    def warnings(self) -> list[str]:
        """The texts of the findings that qualify or annotate the estimate, in order."""
        return note_texts(self.findings)

    def plus_term(self, term: Term, covariance: np.ndarray) -> IdentificationResult:
        """A copy with ``covariance`` (p, p) added to the covariance as ``term`` of its ledger."""
        ledger = self.ledger if self.ledger is not None else Ledger.of(Term.SENSOR_NOISE, self.covariance)
        return dataclasses.replace(self, covariance=self.covariance + covariance, ledger=ledger.plus(term, covariance))

    def budget(self, index: int) -> dict[str, float]:
        """Each ledger term's standard uncertainty of parameter ``index`` (empty without a ledger)."""
        return {} if self.ledger is None else self.ledger.contributions(index)

    def with_findings(self, *findings: Finding, first: bool = False) -> IdentificationResult:
        """A copy with ``findings`` added after (or, ``first``, before) its own."""
        joined = (*findings, *self.findings) if first else (*self.findings, *findings)
        return dataclasses.replace(self, findings=joined)

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
