"""What a full identification's model checks chose, held for cheaper refits of newer samples of the same arm."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.core.findings import Finding
from bsp_ros.core.identification.joint.curves import CurveBasis
from bsp_ros.core.identification.ledger import Ledger
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.result import ParameterName


@dataclass(frozen=True, kw_only=True)
class HeldModel:
    """The choices and verdict of one identification with its model checks (:func:`identify_joint`).

    A live window refits newer samples with them between checks (:func:`refit_held`): the parameters and the
    fit's own (HAC) covariance are the newer data's, everything the checks decided is held.

    Attributes
    ----------
    names : (p,) the parameters.
    passive : the passive model the estimate used (a data-chosen one, fixed).
    widths_rad_s : (n,) friction transition widths (0: a sign step).
    drift : a drifting wrench offset was found and is modelled.
    placement_sd_m : (n + 1,) the chain points' placement sd (m): their share of the covariance follows the
        motion in the window, and a refit computes it anew.
    systematic : the terms of the estimate's covariance beyond its fit's own and the placement's: the passive
        model's choice, the friction shape, the drift's unknown level. These do not shrink with more samples, and a
        few seconds more of the same arm hardly change them.
    noise_scale : (p,) each parameter's sensor-noise std on the residual the marker offsets leave over its std on
        the raw residual (ones without a placement): a refit rescales its own covariance by it.
    placement_factor : (p,) each parameter's placement std with the fit's weights following the offsets over the
        linear response's at the fit's weights (ones without a placement, placement_reweighting.py): a refit
        rescales its linear placement term by it.
    curves : the passive curves' basis (a model choice), or None.
    data_problems : why the samples could not support the estimate (excitation, misfit, identifiability): a refit
        judges its own samples' instead.
    check_problems : what the model checks found the model lacks (an elastic term, Stribeck-like friction, an
        implausible off-axis moment): the verdict a refit holds.
    warnings : the estimate's notes on its model (weak and note findings).
    diagnostics : the estimate's diagnostics.
    """

    names: list[ParameterName]
    passive: PassiveModel
    widths_rad_s: np.ndarray
    drift: bool
    placement_sd_m: np.ndarray
    systematic: Ledger
    noise_scale: np.ndarray
    curves: CurveBasis | None
    data_problems: tuple[Finding, ...]
    check_problems: tuple[Finding, ...]
    warnings: tuple[Finding, ...]
    diagnostics: dict[str, object]
    placement_factor: np.ndarray | None = None
