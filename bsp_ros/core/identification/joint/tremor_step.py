"""Tremor measured, taken out of the torques the model is fitted to, and what it means for the estimate."""

from __future__ import annotations

import dataclasses

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.stage import Outcome, Stage
from bsp_ros.core.identification.joint.tremor import band_stopped, tremor_in
from bsp_ros.core.identification.ledger import Term
from bsp_ros.core.identification.rate import identification_rate_hz
from bsp_ros.core.streams import joints_for

__all__ = ["MIN_DITHER_SHARE", "MIN_TREMOR_NM", "calm_tremor", "dithered_share", "widen_dithered_friction"]

# Tremor torque below this is not reported (no rehab cell's sensor resolves it at a joint), Nm RMS.
MIN_TREMOR_NM = 0.005

# A joint whose tremor-band speed (2 pi f times the angle's RMS in the band) is more than this share of its
# typical speed (the median of its direction-of-motion speed) has its friction dithered: at each instant the
# tremor, not the slow motion, decides the direction friction acts in.
MIN_DITHER_SHARE = 0.5


def _findings(
    joints: tuple[str, ...] | list[str],
    coulomb: bool,
    frequency_hz: float,
    torque_nm: np.ndarray,
    angle_deg: np.ndarray,
    dither_share: np.ndarray,
) -> list[Finding]:
    """The tremor note at its strongest joint, and a friction warning at each joint it shook."""
    worst = int(np.argmax(torque_nm))
    values = {"frequency_hz": frequency_hz, "torque_nm": float(torque_nm[worst]), "angle_deg": float(angle_deg[worst])}
    out = [Finding(code=FindingCode.TREMOR, where=joints[worst], values=values)]
    if coulomb:
        for j in np.flatnonzero(dither_share > MIN_DITHER_SHARE):
            dither = {
                "angle_deg": float(angle_deg[j]),
                "frequency_hz": frequency_hz,
                "speed_percent": float(100.0 * dither_share[j]),
            }
            out.append(Finding(code=FindingCode.TREMOR_FRICTION, where=joints[j], values=dither))
    return out


def calm_tremor(data: IdentificationData, config: JointConfig) -> tuple[IdentificationData, list[Finding]]:
    """``data`` with tremor (:func:`tremor_in`) taken out of its joint torques (a band stop), and what was found:
    its frequency and size, and where it shook a joint, that the friction shown is the session's. Before the
    samples are chosen: a tremor's swings would otherwise be taken for wrench spikes."""
    rate_hz = identification_rate_hz(data.t_ns)
    torque = tremor_in(data.tau_nm, rate_hz)
    present = torque.present & (torque.rms > MIN_TREMOR_NM)
    if not present.any():
        return data, []
    angle = tremor_in(data.q_rad, rate_hz)
    angle_rad = np.where(angle.present, angle.rms, 0.0)
    typical_rad_s = np.median(np.abs(data.velocity_rad_s), axis=0)
    dither_share = 2.0 * np.pi * angle.frequency_hz * angle_rad / np.maximum(typical_rad_s, 1e-9)
    calmed = dataclasses.replace(data, tau_nm=band_stopped(data.tau_nm, rate_hz, present))
    coulomb = "coulomb" in config.passive.terms
    found = _findings(
        joints_for(data.n_joints),
        coulomb,
        torque.frequency_hz,
        np.where(present, torque.rms, 0.0),
        np.degrees(angle_rad),
        np.nan_to_num(dither_share),
    )
    return calmed, found


def dithered_share(speed_rad_s: np.ndarray, dither_rms_rad_s: float) -> float:
    """The share of a Coulomb amplitude a sinusoidal dither of RMS speed ``dither_rms_rad_s`` leaves a slow motion of
    speeds ``speed_rad_s`` (the joint's rows): at each instant friction opposes the sum of both, so averaged over a
    dither period it acts with ``2 / pi * arcsin(v / v_peak)`` of its amplitude where the slow speed ``v`` is below
    the dither's peak ``v_peak``, in full above it."""
    peak = np.sqrt(2.0) * dither_rms_rad_s
    if peak <= 0 or speed_rad_s.size == 0:
        return 1.0
    return float(np.mean(2.0 / np.pi * np.arcsin(np.minimum(1.0, np.abs(speed_rad_s) / peak))))


def widen_dithered_friction(stage: Stage) -> Stage:
    """A Coulomb amplitude a tremor dithered is this session's, lowered by the shaking to about
    :func:`dithered_share` of the relaxed arm's: what that hides (the amplitude over the share, less the
    amplitude) joins its variance as one sd (the friction-shape term), so that its std covers the relaxed arm's
    friction too."""
    dithered = [f for f in stage.notes if f.code is FindingCode.TREMOR_FRICTION]
    if not dithered or "coulomb" not in stage.config.passive.terms:
        return stage
    term = np.zeros_like(stage.fit.covariance)
    joints = list(joints_for(stage.n))
    for finding in dithered:
        j = joints.index(finding.where)
        index = stage.config.passive.local_column("coulomb", stage.n, j)
        dither_rad_s = 2.0 * np.pi * float(finding.values["frequency_hz"]) * np.radians(finding.values["angle_deg"])
        rows = stage.samples.rows[:, j]
        share = max(dithered_share(stage.data.velocity_rad_s[rows, j], dither_rad_s), 0.05)
        term[index, index] = (abs(stage.fit.values[index]) * (1.0 / share - 1.0)) ** 2
    return stage.apply(Outcome(added=((Term.FRICTION_SHAPE, term),)))
