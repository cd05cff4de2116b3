"""Which rows tell the direction of motion, and whether the motion excites every joint."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.streams import joints_for


def deadband_rad_s(data: IdentificationData, config: JointConfig) -> np.ndarray:
    """(n,) each joint's direction dead band, rad/s: below it the sign of the direction velocity is not trusted
    (``deadband_fraction`` of the typical speed, the 95th percentile, or ``deadband_noise_sd`` times its noise)."""
    typical = np.percentile(np.abs(data.velocity_rad_s), 95, axis=0)
    noise = np.nan_to_num(data.velocity_noise_rad_s, nan=0.0)
    return np.asarray(np.maximum(config.deadband_fraction * typical, config.deadband_noise_sd * noise))


def motion_rows(data: IdentificationData, config: JointConfig) -> tuple[np.ndarray, list[Finding]]:
    """Rows with a trustworthy direction of motion (all rows when the model has no Coulomb term)."""
    speed = np.abs(data.velocity_rad_s)
    if "coulomb" not in config.passive.terms:
        return np.ones_like(speed, dtype=bool), []
    typical = np.percentile(speed, 95, axis=0)
    noise = np.nan_to_num(data.velocity_noise_rad_s, nan=0.0)
    deadband = deadband_rad_s(data, config)
    notes = []
    for j, joint in enumerate(joints_for(data.n_joints)):
        if noise[j] > 0 and config.deadband_noise_sd * noise[j] > 0.5 * typical[j]:
            notes.append(
                Finding(
                    code=FindingCode.DIRECTION_NOISY,
                    where=joint,
                    values={"noise_rad_s": float(noise[j]), "typical_rad_s": float(typical[j])},
                )
            )
    return speed > deadband[None, :], notes


def excitation_problems(data: IdentificationData, rows: np.ndarray, config: JointConfig) -> list[Finding]:
    """Why the motion cannot support an estimate: too few samples, a joint that does not move, or (with a
    Coulomb term) one that moves in one direction only among the ``rows`` (N, n) of trustworthy direction."""
    problems = []
    if data.t_ns.size < config.min_samples:
        problems.append(
            Finding(
                code=FindingCode.TOO_FEW_SAMPLES, values={"n": int(data.t_ns.size), "min_samples": config.min_samples}
            )
        )
        return problems
    range_deg = np.degrees(np.ptp(data.q_rad, axis=0))
    for j, joint in enumerate(joints_for(data.n_joints)):
        if range_deg[j] < config.min_range_deg:
            problems.append(
                Finding(
                    code=FindingCode.NO_MOTION,
                    where=joint,
                    values={"range_deg": float(range_deg[j]), "min_range_deg": config.min_range_deg},
                )
            )
        elif "coulomb" in config.passive.terms:
            signs = np.sign(data.velocity_rad_s[rows[:, j], j])
            share = min((signs > 0).mean(), (signs < 0).mean()) if signs.size else 0.0
            if share < config.min_direction_share:
                problems.append(
                    Finding(code=FindingCode.ONE_DIRECTION, where=joint, values={"other_percent": float(100 * share)})
                )
    return problems
