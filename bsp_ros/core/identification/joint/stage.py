"""Where a stacked identification stands between its steps, and the one shape of what each step found."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bsp_ros.core.findings import Finding
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.elastic import ElasticReference
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.curves import CurveBasis
from bsp_ros.core.identification.joint.drift import Drift, DriftSpans
from bsp_ros.core.identification.joint.placement_covariance import PlacementEffect
from bsp_ros.core.identification.joint.placement_scale import PlacementScale
from bsp_ros.core.identification.joint.samples import Samples
from bsp_ros.core.identification.ledger import Ledger, Term
from bsp_ros.core.identification.result import IdentificationResult, ParameterName
from bsp_ros.core.identification.selection import Selection
from bsp_ros.core.identification.stacked import Fit, Problem

__all__ = ["Outcome", "Stage", "Step"]


@dataclass(frozen=True, kw_only=True)
class Outcome:
    """What one step of the identification found.

    Attributes
    ----------
    problem : the problem the estimate now rests on (other samples or terms), or None to keep it.
    fit : a replacement fit; its covariance is the new sensor-noise term of the ledger. None keeps the fit.
    added : covariance terms (p, p) added to the ledger.
    replaced : covariance terms that replace the ledger's of the same name.
    notes : weak and note findings, in order.
    problems : findings that make the estimate invalid.
    """

    problem: Problem | None = None
    fit: Fit | None = None
    added: tuple[tuple[Term, np.ndarray], ...] = ()
    replaced: tuple[tuple[Term, np.ndarray], ...] = ()
    notes: tuple[Finding, ...] = ()
    problems: tuple[Finding, ...] = ()


@dataclass(frozen=True, kw_only=True)
class Stage:
    """An identification between two of its steps.

    ``fit.covariance`` is always ``ledger``'s total: what a step reads as the estimate's covariance holds every
    term the steps before it added.

    Attributes
    ----------
    data, config : what is identified and how; ``config.passive`` is the model chosen so far.
    placement_sd_m : (n + 1,) each chain point's assumed placement sd, m.
    samples : the usable samples (rows per joint, wrench spikes, dynamics blocks).
    problem, fit : the stacked problem and its fit.
    ledger : the estimate's covariance, term by term.
    widths_rad_s, spread_nm : (n,) friction transition widths and the Coulomb amplitudes' spread over them.
    selection : the passive model the data chose (``--passive auto``), or None.
    probed : the candidates the std must cover (the selection, or a nonlinear model's shape probe), or None.
    notes : weak and note findings, in order; ``sample_notes`` those of the samples among the model's.
    data_notes : how many of ``notes`` came with the samples (before any step).
    data_problems, check_problems : findings that make the estimate invalid, from the data and the model checks.
    removed : fit outliers removed.
    prior_share : posterior over prior variance of each parameter with a prior.
    placement, placement_fit : the markers' placement effect and the fit it was computed at.
    noise_scale : (p,) the sensor-noise std on the offsets' residual over that on the raw residual, or None.
    judged_residual : (N, n) the residual the misfit check judges (less what placement explains), or None.
    drift : a drift the data show and its model, or None.
    curves : the passive curves' basis, or None; passive_curves : the curves at the judged fit; elastic_reference :
        the angles the elastic terms are referred to. noise_nm, misfit : per joint, the sensor noise and the residual
        RMS over it.
    max_corr_with_gravity : each passive term's largest correlation with a static moment.
    drift_terms : a drift's columns (:func:`drift_columns`), once computed.
    with_springs : the problem with a linear spring's terms beside this one's, where a check needs it.
    placement_check : what the data say of the markers' placement, or None.
    slip_alternatives : (N, n) torques under other plausible estimates of a slipping hand's travel, whose fits
        bound what following it leaves open (none without a slip).
    unslipped : the data before a slipping hand's travel was taken out of their torques (None without a slip): a
        fallback that identifies the session afresh starts from them and follows the hand with its own model.
    stuck : (N, n) the samples each joint stuck in a compliant grip, kept out of its rows (``grip.py``), or None.
    """

    data: IdentificationData
    config: JointConfig
    placement_sd_m: np.ndarray
    samples: Samples
    problem: Problem
    fit: Fit
    ledger: Ledger
    widths_rad_s: np.ndarray
    spread_nm: np.ndarray
    selection: Selection | None = None
    probed: Selection | None = None
    notes: tuple[Finding, ...] = ()
    sample_notes: tuple[Finding, ...] = ()
    data_notes: int = 0
    data_problems: tuple[Finding, ...] = ()
    check_problems: tuple[Finding, ...] = ()
    removed: int = 0
    prior_share: dict[str, float] = field(default_factory=dict)
    placement: PlacementEffect | None = None
    placement_fit: Fit | None = None
    noise_scale: np.ndarray | None = None
    judged_residual: np.ndarray | None = None
    drift: Drift | None = None
    curves: CurveBasis | None = None
    passive_curves: dict[str, Any] = field(default_factory=dict)
    elastic_reference: ElasticReference | None = None
    noise_nm: np.ndarray | None = None
    misfit: np.ndarray | None = None
    max_corr_with_gravity: dict[str, float] = field(default_factory=dict)
    drift_terms: tuple[np.ndarray, list[ParameterName], DriftSpans] | None = None
    with_springs: Problem | None = None
    placement_check: PlacementScale | None = None
    slip_alternatives: tuple[np.ndarray, ...] = ()
    unslipped: IdentificationData | None = None
    stuck: np.ndarray | None = None

    @property
    def n(self) -> int:
        """Joints."""
        return self.data.n_joints

    @property
    def given(self) -> IdentificationData:
        """The data as the steps were given them (before a slipping hand was followed), for a fallback."""
        return self.data if self.unslipped is None else self.unslipped

    @property
    def problems(self) -> tuple[Finding, ...]:
        """Every finding so far that makes the estimate invalid."""
        return (*self.data_problems, *self.check_problems)

    def apply(self, outcome: Outcome, *, from_checks: bool = False) -> Stage:
        """This stage with ``outcome``: its problem and fit, its terms in the ledger, its findings (``from_checks``:
        its problems are a model check's verdict, held between a live window's checks)."""
        ledger = self.ledger
        if outcome.fit is not None:
            ledger = ledger.with_term(Term.SENSOR_NOISE, outcome.fit.covariance)
        for term, covariance in outcome.added:
            ledger = ledger.plus(term, covariance)
        for term, covariance in outcome.replaced:
            ledger = ledger.with_term(term, covariance)
        fit = outcome.fit if outcome.fit is not None else self.fit
        data_problems, check_problems = self.data_problems, self.check_problems
        if from_checks:
            check_problems = (*check_problems, *outcome.problems)
        else:
            data_problems = (*data_problems, *outcome.problems)
        return dataclasses.replace(
            self,
            problem=outcome.problem if outcome.problem is not None else self.problem,
            fit=dataclasses.replace(fit, covariance=ledger.total(fit.values.size)),
            ledger=ledger,
            notes=(*self.notes, *outcome.notes),
            data_problems=data_problems,
            check_problems=check_problems,
        )


# One step of the identification: the next stage, or the result where the step decides it (a fallback).
Step = Callable[[Stage], "Stage | IdentificationResult"]
