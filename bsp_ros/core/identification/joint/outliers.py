"""Samples left out: wrench spikes before the fit, samples far off it after, and where gaps lie."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.robust import hampel_outliers, robust_sd
from bsp_ros.core.identification.stacked import Fit

# Torque deviations and misfits below this never count (Nm): no rehab cell's sensor resolves them, and a
# noise-free simulation would otherwise be judged against its rounding errors.
MIN_OUTLIER_NM = 1e-3


def wrench_spikes(data: IdentificationData, config: JointConfig) -> tuple[np.ndarray, list[Finding]]:
    """Samples whose torques jump off the rolling median of their neighbours (wrench spikes), or not finite."""
    finite = np.isfinite(data.tau_nm).all(axis=1)
    flags = ~finite
    if finite.sum() >= 3:
        flags[finite] = hampel_outliers(
            data.tau_nm[finite], config.spike_window, config.outlier_sd, floor=MIN_OUTLIER_NM
        )
    count = int(flags.sum())
    if not count:
        return flags, []
    values = {"n": count, "outlier_sd": config.outlier_sd, "window": config.spike_window}
    return flags, [Finding(code=FindingCode.WRENCH_SPIKES_REMOVED, values=values)]


def fit_outliers(fit: Fit, config: JointConfig) -> np.ndarray:
    """(N,) samples with a residual beyond ``outlier_sd`` robust standard deviations at any joint."""
    scale = robust_sd(fit.residual, axis=0)
    with np.errstate(invalid="ignore"):
        far = np.abs(fit.residual) > np.maximum(config.outlier_sd * scale, MIN_OUTLIER_NM)[None, :]
    return np.asarray(far.any(axis=1))


# More samples far off the fit than this share of the usable ones: the model does not fit (nothing is removed).
MAX_FAR_SHARE = 0.05


def too_far_off(n_far: int, usable: int) -> bool:
    """Whether ``n_far`` samples far off the fit (:func:`fit_outliers`) of ``usable`` mean the model does not fit."""
    return n_far > MAX_FAR_SHARE * usable


def far_off_problem(n_far: int, usable: int, config: JointConfig) -> Finding:
    """The problem of a fit that too many samples lie far off (:func:`too_far_off`)."""
    values = {"n_far": n_far, "usable": usable, "outlier_sd": config.outlier_sd}
    return Finding(code=FindingCode.FAR_OFF_SAMPLES, values=values)


# Samples this close to a gap in the data (angles lost to marker dropouts) sit where the direction filter
# has least support; far-off samples there are named as such (seen at 0-0.2 s in simulated dropouts).
GAP_EDGE_S = 0.25


def near_gaps(t_ns: np.ndarray, edge_s: float) -> np.ndarray:
    """(N,) samples within ``edge_s`` of a gap: consecutive stamps more than 3 median periods apart."""
    near = np.zeros(t_ns.size, dtype=bool)
    if t_ns.size < 3:
        return near
    step = np.diff(t_ns)
    gaps = np.flatnonzero(step > 3 * np.median(step))
    if gaps.size == 0:
        return near
    edges = np.sort(np.concatenate([t_ns[gaps], t_ns[gaps + 1]]))  # the last sample before, first after
    position = np.searchsorted(edges, t_ns)
    before = np.abs(t_ns - edges[np.clip(position - 1, 0, edges.size - 1)])
    after = np.abs(edges[np.clip(position, 0, edges.size - 1)] - t_ns)
    return np.asarray(np.minimum(before, after) <= edge_s * 1e9)
