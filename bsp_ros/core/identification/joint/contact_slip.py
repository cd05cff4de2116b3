"""A hand that slips in the handle: the contact point drifting along the hand during a session.

A hand strapped to a handle is not fixed to it: under the arm's weight it slides by millimetres to a centimetre
over a session. Moving the point where the force acts by ``s`` along the last segment changes every joint's torque
by the same ``s * g``, with ``g = sin(phi_n) F_y - cos(phi_n) F_z`` (the force's lever about the hand's
direction; :func:`contact_torques_nm`). So the residual common to all joints, regressed on ``g`` window by window,
gives the contact point's travel; a slip accumulates, so the travel follows a trend through the session, where
bursts of activity or a misfit give windows of either sign.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from bsp_ros.core.model import absolute_angles_rad, contact_lever_sums

__all__ = ["Slip", "contact_slip", "slip_lever_n"]

# The travel is estimated window by window, s.
WINDOW_S = 10.0

# Each joint's own travel trend is at least this share of the largest one's under a slip (a fit takes up part of
# it differently at each joint: 0.4 and more on the MuJoCo slipping hand; a vertical force drift gives 0.15).
MIN_JOINT_AGREEMENT = 0.3

# A trend explaining less of the windows' travel than this is no slip (bursts, a misfit, skin markers).
MIN_TREND_SHARE = 0.6


@dataclass(frozen=True, kw_only=True)
class Slip:
    """The contact point's travel along the hand.

    Attributes
    ----------
    travel_m : (N,) the travel at each sample since the session's start, m (zeros without a slip).
    total_m : how far the contact point went from the session's start to its end, m.
    trend_share : the share of the windows' travel variance its linear trend explains.
    """

    travel_m: np.ndarray
    total_m: float
    trend_share: float


def slip_lever_n(q_rad: np.ndarray, lengths_m: np.ndarray, tau_nm: np.ndarray) -> np.ndarray:
    """(N,) ``g``, N: the torque at every joint per metre the contact point moves along the hand. The contact
    wrench is recovered from the torques of a 3-joint chain (``tau = -J^T w``); other chains give zeros."""
    n = q_rad.shape[1]
    if n != 3:
        return np.zeros(q_rad.shape[0])
    dy, dz = contact_lever_sums(q_rad, lengths_m)
    levers = np.stack((dy, dz, np.ones_like(dy)), axis=2)
    finite = np.isfinite(tau_nm).all(axis=1)
    wrench = np.zeros((q_rad.shape[0], 3))
    wrench[finite] = np.linalg.solve(levers[finite], -tau_nm[finite, :, None])[..., 0]
    phi = absolute_angles_rad(q_rad)[:, -1]
    return np.asarray(np.sin(phi) * wrench[:, 0] - np.cos(phi) * wrench[:, 1])


def contact_slip(t_ns: np.ndarray, residual_nm: np.ndarray, lever_n: np.ndarray, window_s: float = WINDOW_S) -> Slip:
    """The contact point's travel along the hand from a fit's residual (N, n; NaN off its rows) and the lever
    ``lever_n`` (N,) of :func:`slip_lever_n`, window by window of ``window_s``.

    Returns
    -------
    Slip; ``total_m`` 0 where the session is shorter than four windows.
    """
    none = Slip(travel_m=np.zeros(t_ns.size), total_m=0.0, trend_share=0.0)
    t_s = (t_ns - t_ns[0]) * 1e-9
    if t_s[-1] < 4 * window_s or not lever_n.any():
        return none
    finite = np.isfinite(residual_nm)
    count = finite.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        common = np.where(count > 0, np.where(finite, residual_nm, 0.0).sum(axis=1) / count, np.nan)
    usable = np.isfinite(common)
    centres, travel, per_joint = [], [], []
    for start in np.arange(0.0, t_s[-1], window_s):
        rows = usable & (t_s >= start) & (t_s < start + window_s)
        weight = float(lever_n[rows] @ lever_n[rows])
        if rows.sum() < 20 or weight <= 0:
            continue
        centres.append(float(t_s[rows].mean()))
        travel.append(float(common[rows] @ lever_n[rows]) / weight)
        per_joint.append(np.where(finite[rows], residual_nm[rows], 0.0).T @ lever_n[rows] / weight)
    if len(travel) < 4:
        return none
    x, y = np.asarray(centres), np.asarray(travel)
    slope, intercept = np.polyfit(x, y, 1)
    # A slip moves every joint's torque alike; a drifting force sensor moves each by its lever (the shoulder's
    # several times the wrist's), a drifting moment alike but with no tie to the force's lever.
    slopes = np.polyfit(x, np.asarray(per_joint), 1)[0]
    if (
        not (np.sign(slopes) == np.sign(slope)).all()
        or np.abs(slopes).min() < MIN_JOINT_AGREEMENT * np.abs(slopes).max()
    ):
        return dataclasses.replace(none, trend_share=0.0)
    spread = float(np.var(y))
    share = 1.0 - float(np.var(y - (slope * x + intercept))) / spread if spread > 0 else 0.0
    along = np.interp(t_s, x, y)
    return Slip(travel_m=along - along[0], total_m=float(abs(slope) * (x[-1] - x[0])), trend_share=share)
