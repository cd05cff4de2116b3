"""Tremor measured, taken out of the torques the model is fitted to, and what it means for the estimate."""

from __future__ import annotations

import dataclasses

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.tremor import band_stopped, tremor_in
from bsp_ros.core.streams import joints_for

__all__ = ["MIN_DITHER_DEG", "MIN_TREMOR_NM", "calm_tremor"]

# Tremor torque below this is not reported (no rehab cell's sensor resolves it at a joint), Nm RMS.
MIN_TREMOR_NM = 0.005

# A joint shaken by more than this has its friction dithered, deg RMS in the tremor band.
MIN_DITHER_DEG = 0.05


def _rate_hz(t_ns: np.ndarray) -> float:
    step = np.diff(t_ns)
    return 1e9 / float(np.median(step)) if step.size else 0.0


def _findings(
    joints: tuple[str, ...] | list[str],
    coulomb: bool,
    frequency_hz: float,
    torque_nm: np.ndarray,
    angle_deg: np.ndarray,
) -> list[Finding]:
    """The tremor note at its strongest joint, and a friction warning at each joint it shook."""
    worst = int(np.argmax(torque_nm))
    values = {"frequency_hz": frequency_hz, "torque_nm": float(torque_nm[worst]), "angle_deg": float(angle_deg[worst])}
    out = [Finding(code=FindingCode.TREMOR, where=joints[worst], values=values)]
    if coulomb:
        for j in np.flatnonzero(angle_deg > MIN_DITHER_DEG):
            dither = {"angle_deg": float(angle_deg[j]), "frequency_hz": frequency_hz}
            out.append(Finding(code=FindingCode.TREMOR_FRICTION, where=joints[j], values=dither))
    return out


def calm_tremor(data: IdentificationData, config: JointConfig) -> tuple[IdentificationData, list[Finding]]:
    """``data`` with tremor (:func:`tremor_in`) taken out of its joint torques (a band stop), and what was found:
    its frequency and size, and where it shook a joint, that the friction shown is the session's. Before the
    samples are chosen: a tremor's swings would otherwise be taken for wrench spikes."""
    rate_hz = _rate_hz(data.t_ns)
    torque = tremor_in(data.tau_nm, rate_hz)
    present = torque.present & (torque.rms > MIN_TREMOR_NM)
    if not present.any():
        return data, []
    angle = tremor_in(data.q_rad, rate_hz)
    angle_deg = np.where(angle.present, np.degrees(angle.rms), 0.0)
    calmed = dataclasses.replace(data, tau_nm=band_stopped(data.tau_nm, rate_hz, present))
    coulomb = "coulomb" in config.passive.terms
    found = _findings(
        joints_for(data.n_joints), coulomb, torque.frequency_hz, np.where(present, torque.rms, 0.0), angle_deg
    )
    return calmed, found
