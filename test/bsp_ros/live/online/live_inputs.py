"""A simulated session as the live identifier receives it (shared by these tests and bench/live_window_update.py)."""

from __future__ import annotations

import numpy as np

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.data import wrench_world_yzx
from bsp_ros.live.online.causal_angles import CausalJointAngles


def live_inputs(spec: sim.CellSpec):
    """Simulate ``spec`` and feed its markers through the causal angle estimator, as the live nodes would see it.

    Returns (simulated session, wrench stamps, world wrench (N, 3), causal angle samples stamped by group delay,
    unfiltered angles (t_ns, q_rad, lengths_m) per accepted frame).
    """
    simulated = sim.simulate_cell(spec)
    session = simulated.session
    frames: dict[int, dict[str, np.ndarray]] = {}
    for name, series in session.markers.items():
        for t, p in zip(series.t_ns, series.position_m, strict=True):
            frames.setdefault(int(t), {})[name] = p
    estimator = CausalJointAngles(3)
    delay_ns = int(estimator.group_delay_s() * 1e9)
    angles, raw = [], []
    for t in sorted(frames):
        sample = estimator.update(t, frames[t])
        if estimator.accepted(t):
            raw.append((t, estimator.last_raw_q_rad, estimator.lengths_m))
        if sample is not None:
            angles.append((t - delay_ns, sample))
    wrench = wrench_world_yzx(session.wrench, session.rotation_world_from_sensor)
    return simulated, session.wrench.t_ns, wrench, angles, raw
