"""A simulated session as the live identifier receives it, and the recursive mode run on it as the node runs it
(shared by these tests and the live benchmarks)."""

from __future__ import annotations

import time

import numpy as np

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.data import wrench_world_yzx
from bsp_ros.core.pipeline import IdentifyOptions, recursive_estimate
from bsp_ros.live.online.causal_angles import CausalJointAngles
from bsp_ros.live.online.recursive_check import WindowCheck
from bsp_ros.live.online.recursive_feed import RecursiveFeed
from bsp_ros.live.online.windowed import WindowConfig, WindowedIdentifier

PERIOD_NS = 200_000_000  # the identifier's 5 Hz


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


class WindowFeed:
    """Feeds a :class:`WindowedIdentifier` the unfiltered angles and wrenches of :func:`live_inputs`, in order, up to a
    stamp at a time (as the node's callbacks take them between two updates)."""

    def __init__(self, identifier: WindowedIdentifier, stamps: np.ndarray, wrench: np.ndarray, raw: list) -> None:
        self.identifier, self.stamps, self.wrench, self.raw = identifier, stamps, wrench, raw
        self._wrench_i = self._angle_i = 0

    def until(self, t_ns: int) -> None:
        """Add every sample stamped at or before ``t_ns`` not added yet."""
        raw, stamps = self.raw, self.stamps
        while self._angle_i < len(raw) and raw[self._angle_i][0] <= t_ns:
            self.identifier.add_joint_state(*raw[self._angle_i])
            self._angle_i += 1
        while self._wrench_i < len(stamps) and stamps[self._wrench_i] <= t_ns:
            self.identifier.add_wrench(int(stamps[self._wrench_i]), self.wrench[self._wrench_i])
            self._wrench_i += 1


def orientation(simulated: sim.SimulatedSession) -> tuple[str, np.ndarray]:
    """The wrench sensor's frame and rotation into ``world`` (its last, if it turns), as the node passes them."""
    rotation = np.asarray(simulated.session.rotation_world_from_sensor, dtype=np.float64)
    return simulated.session.wrench.frame_id, rotation if rotation.ndim == 2 else rotation[-1]


def recursive_mode(inputs, options: IdentifyOptions, window_s: float = 30.0, from_ns: int = 0, checked: bool = True):
    """The recursive mode as ``bsp_identifier`` runs it on :func:`live_inputs`: the filter on the causal joint states
    and every wrench, its window (the unfiltered angles, every wrench) identified with every model check every 10 s,
    and every 0.2 s the filter's estimate held to it (``checked``; else the filter's alone) as a document.

    Returns the documents and their compute times (s, the window checks included) of the updates at or after
    ``from_ns``.
    """
    simulated, stamps, wrench, states, raw = inputs
    feed = RecursiveFeed(3, options.passive, options.subject)
    window = WindowedIdentifier(3, WindowConfig(window_s=window_s, options=options, elastic_check_every=1))
    check = WindowCheck(window)
    frame = orientation(simulated)
    tick_ns = int(stamps[0]) + PERIOD_NS
    documents, seconds = [], []
    k = a = 0
    lengths = states[0][1].lengths_m
    for i, t_ns in enumerate(stamps.tolist()):
        while tick_ns < t_ns:
            started = time.perf_counter()
            check.tick(frame)
            result = feed.identifier.result()
            document = recursive_estimate(check.checked(result) if checked else result, lengths, options).to_json()
            if tick_ns >= from_ns:
                documents.append(document)
                seconds.append(time.perf_counter() - started)
            tick_ns += PERIOD_NS
        while a < len(raw) and raw[a][0] <= t_ns:
            window.add_joint_state(raw[a][0], raw[a][1], raw[a][2])
            a += 1
        while k < len(states) and states[k][0] <= t_ns:
            lengths = states[k][1].lengths_m
            feed.add_joint_state(states[k][0], states[k][1].q_rad, states[k][1].velocity_rad_s, lengths)
            k += 1
        feed.add_wrench(t_ns, wrench[i], lengths)
        window.add_wrench(t_ns, wrench[i])
    return documents, seconds
