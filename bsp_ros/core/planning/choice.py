"""What `bsp identify --passive auto` will choose on a plan's sessions, and the model-choice std it will report.

With ``auto`` identify fits every candidate passive model, keeps the one the data choose, and adds to each of its
parameters the largest squared difference to the estimate of any candidate the data cannot reject (and, for a
nonlinear choice, to its shape probe, with the probe's excess variance): ``identification.selection``
``spread_covariance``. That term is one draw of a difference between two fits of the same samples; its
expectation is what a plan can promise. Every fit is linear in the torques, so each difference is a linear map of
what perturbs them (the sensor noise, the markers' placement, the sensor's zero): ``d_k = (R_k - R_c) s`` with
``s = X^T W dtau`` the perturbation's scores over the columns of every model involved and ``R_m`` model ``m``'s
response to them. The expected largest square over the candidates is then a small Gaussian integral, taken by a
seeded Monte Carlo.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from bsp_ros.core.identification.covariance import design_inverse
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.result import ParameterName
from bsp_ros.errors import InputError

__all__ = ["AutoChoice", "ScoreCovariance", "expected_choice_variance", "response_matrix"]

#: Draws of the Monte Carlo that takes the expected largest square (seeded: the same plan, the same prediction).
CHOICE_DRAWS = 4000


@dataclass(frozen=True, kw_only=True)
class AutoChoice:
    """The passive model `bsp identify --passive auto` chose on the plan's simulated check session (the nominal
    arm with the cell's nonlinear, coupled passive moments), and the models its data could not reject.

    Attributes
    ----------
    chosen : the model identify chose there; the plan's predicted std is that model's.
    open_models : the other candidates the check session's data did not reject (their spread is in the std).
    check_valid : whether the check session's estimate was valid.
    """

    chosen: PassiveModel
    open_models: tuple[PassiveModel, ...]
    check_valid: bool

    @classmethod
    def from_estimate(cls, estimate: dict[str, object], passive: PassiveModel) -> AutoChoice:
        """The choice an estimate document (docs/contract.md) records: ``diagnostics.passive_model`` and the
        candidates of ``diagnostics.passive_selection`` that are not ``rejected``; ``passive`` is the family asked
        for (``auto``).

        Raises
        ------
        InputError
            The document records no choice among ``passive``'s candidates.
        """
        diagnostics = estimate.get("diagnostics")
        quality = estimate.get("quality")
        if not isinstance(diagnostics, dict) or not isinstance(diagnostics.get("passive_model"), str):
            # An invalid estimate of data that cannot tell a model (a joint still) chooses none: say why.
            why = quality.get("message") if isinstance(quality, dict) and not quality.get("valid") else None
            cause = f": it is not valid ({why})" if why else ""
            raise InputError(f"the check session's estimate records no passive model{cause}")
        candidates = {model.label: model for model in passive.candidates()}
        chosen = candidates.get(diagnostics["passive_model"])
        if chosen is None:
            raise InputError(f"the check session chose {diagnostics['passive_model']!r}, not a candidate of auto")
        selection = diagnostics.get("passive_selection")
        selection = selection if isinstance(selection, dict) else {}
        open_models = tuple(
            model
            for label, model in candidates.items()
            if model != chosen and isinstance(selection.get(label), dict) and not selection[label].get("rejected")
        )
        valid = bool(quality.get("valid")) if isinstance(quality, dict) else False
        return cls(chosen=chosen, open_models=open_models, check_valid=valid)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: ``chosen`` and ``open_models`` (labels), ``check_valid``."""
        return {
            "chosen": self.chosen.label,
            "open_models": [model.label for model in self.open_models],
            "check_valid": self.check_valid,
        }


@dataclass(frozen=True, kw_only=True)
class ScoreCovariance:
    """The perturbation of a session's scores ``X^T W dtau`` over the union of the models' columns.

    Attributes
    ----------
    names : (q,) the union's parameters.
    design : (q, q) ``X^T W X + P``: the fits' normal matrix, priors included (a model's is its block).
    noise : (q, q) the sensor noise's long-run covariance of the scores plus the priors' ``P`` (what the fit's own
        covariance holds: the sandwich's middle).
    total : (q, q) ``noise`` plus what the marker placement and the sensor zero add to the scores.
    placement : (q, q) what the marker placement alone adds (0 without placement).
    """

    names: list[ParameterName]
    design: np.ndarray
    noise: np.ndarray
    total: np.ndarray
    placement: np.ndarray | None = None


def response_matrix(
    design: np.ndarray, names: Sequence[ParameterName], model_names: Sequence[ParameterName]
) -> np.ndarray:
    """(p, q) how the fit of a model with parameters ``model_names`` (p, a subset of ``names``) moves with the
    union's scores: its block of ``design`` (q, q) inverted, embedded in the union's columns.

    Raises
    ------
    InputError
        A model parameter is not among ``names``.
    """
    missing = [name for name in model_names if name not in names]
    if missing:
        raise InputError(f"parameters {missing} are not among the union's columns")
    index = [list(names).index(name) for name in model_names]
    out = np.zeros((len(index), len(names)))
    out[:, index] = design_inverse(design[np.ix_(index, index)])  # scaled, as the estimator inverts it
    return out


def expected_choice_variance(
    scores: ScoreCovariance,
    chosen: Sequence[ParameterName],
    others: Sequence[tuple[Sequence[ParameterName], bool]],
    draws: int = CHOICE_DRAWS,
    seed: int = 0,
) -> np.ndarray:
    """(p,) per parameter of the chosen model, the expected model-choice variance identify adds: the expected
    largest over the other models ``k`` (their shared parameters) of ``d_k^2``, where ``d_k`` is the difference of
    their fits on the same perturbed session, or, where larger, of what identify takes as its variance: model
    ``k``'s variance beyond the chosen fit's plus the marker placement's share of ``d_k``'s (for a shape probe,
    that variance beyond is added to ``d_k^2``).

    Parameters
    ----------
    scores : the score perturbation over the union's columns.
    chosen : (p,) the chosen model's parameters.
    others : per other model its parameters and whether it is the chosen model's shape probe (whose excess
        variance identify adds to its squared shift).
    draws, seed : the Monte Carlo's draws and seed.
    """
    p = len(chosen)
    if not others:
        return np.zeros(p)
    r_chosen = response_matrix(scores.design, scores.names, chosen)
    differences: list[np.ndarray] = []
    excess: list[np.ndarray] = []
    probes: list[bool] = []
    for names, probe in others:
        r_other = response_matrix(scores.design, scores.names, names)
        rows = np.array([list(names).index(name) if name in names else -1 for name in chosen])
        shared = rows >= 0
        difference = np.zeros_like(r_chosen)
        difference[shared] = r_other[rows[shared]] - r_chosen[shared]
        differences.append(difference)
        extra = np.zeros(p)
        own = np.einsum("ij,jk,ik->i", r_other, scores.noise, r_other)[rows[shared]]
        base = np.einsum("ij,jk,ik->i", r_chosen, scores.noise, r_chosen)[shared]
        extra[shared] = np.clip(own - base, 0.0, None)
        if not probe and scores.placement is not None:
            extra += np.einsum("iq,qr,ir->i", difference, scores.placement, difference)
        excess.append(extra)
        probes.append(probe)
    stacked = np.stack(differences)  # (K, p, q)
    # Per parameter the K differences' covariance, then the expected largest of identify's squared spreads by draws of
    # that K-variate normal.
    covariance = np.einsum("kiq,qr,lir->ikl", stacked, scores.total, stacked)
    rng = np.random.default_rng(seed)
    normal = rng.standard_normal((draws, len(others)))
    out = np.empty(p)
    for i in range(p):
        values, vectors = np.linalg.eigh(0.5 * (covariance[i] + covariance[i].T))
        root = vectors * np.sqrt(np.clip(values, 0.0, None))
        d = normal @ root.T
        extra = np.array([c[i] for c in excess])[None, :]
        # identify's spread: a probe's squared shift plus its excess variance, another model's at least that excess.
        squared = np.where(np.array(probes)[None, :], d**2 + extra, np.maximum(d**2, extra))
        out[i] = float(np.mean(np.max(squared, axis=1)))
    return out
