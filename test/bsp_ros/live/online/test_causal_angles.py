"""Causal joint angles: agreement with the true trajectory and restart across long gaps."""

from __future__ import annotations

import numpy as np

from bsp_ros.core import simulation as sim
from bsp_ros.live.online.causal_angles import CausalJointAngles


def test_group_delay_compensated_angles_follow_the_trajectory(live_streams) -> None:
    simulated, _, _, angles, _ = live_streams
    simulator = sim.CellSimulator(sim.human_arm_cell(seed=13, duration_s=60.0))
    stamps = np.array([t for t, _ in angles])
    q = np.array([a.q_rad for _, a in angles])
    truth = simulator.joint_angles_rad(simulator.seconds_since_start(stamps))
    # 0.1 mm marker noise on an 8.8 cm hand gives ~1e-3 rad per frame before filtering.
    assert np.sqrt(np.mean((q - truth) ** 2, axis=0)).max() < 1.2e-3
    np.testing.assert_allclose(np.array([a.lengths_m for _, a in angles])[-1], simulated.truth.lengths_m, atol=1e-3)


def test_a_long_gap_restarts_the_filters_and_withholds_angles_until_settled(live_streams) -> None:
    simulated, _, _, _, _ = live_streams
    markers = simulated.session.markers
    estimator = CausalJointAngles(3)
    stamps = markers["shoulder"].t_ns
    outputs = []
    for k, t in enumerate(stamps[:1000]):
        if 400 <= k < 450:  # 1 s without any marker
            continue
        frame = {name: series.position_m[k] for name, series in markers.items()}
        outputs.append((k, estimator.update(int(t), frame)))
    assert estimator.n_restarts == 1
    after_gap = [out for k, out in outputs if 450 <= k < 450 + 90]  # settle time is 2 s = 100 frames
    assert all(out is None for out in after_gap)
    assert outputs[-1][1] is not None


def test_a_frame_with_a_missing_or_nan_marker_is_skipped(live_streams) -> None:
    simulated, _, _, _, _ = live_streams
    estimator = CausalJointAngles(3)
    frame = {name: series.position_m[0] for name, series in simulated.session.markers.items()}
    assert estimator.update(1_000, {k: v for k, v in frame.items() if k != "wrist"}) is None
    frame["elbow"] = np.array([np.nan, 0.0, 0.0])
    assert estimator.update(2_000, frame) is None


def _run(estimator: CausalJointAngles, markers: dict, frames: int) -> np.ndarray:
    stamps = markers["shoulder"].t_ns
    out = []
    for k, t in enumerate(stamps[:frames]):
        sample = estimator.update(int(t), {name: series.position_m[k] for name, series in markers.items()})
        out.append(np.full(3, np.nan) if sample is None else sample.q_rad)
    return np.array(out)


def test_a_frame_off_the_rigid_chain_is_rejected_and_counted(live_streams) -> None:
    from bsp_ros.core import glitches

    simulated, _, _, _, _ = live_streams
    clean = _run(CausalJointAngles(3), simulated.session.markers, 600)
    for glitched in (
        glitches.displace_marker(simulated.session, "elbow", 300, (0.0, 0.67, 0.0)),
        glitches.displace_marker(simulated.session, "hand", 300, (0.0, 0.0, 0.06)),
        glitches.swap_markers(simulated.session, "elbow", "hand", 300),
    ):
        estimator = CausalJointAngles(3)
        q = _run(estimator, glitched.markers, 600)
        assert estimator.n_rejected == 1 and estimator.n_restarts == 0
        assert np.isnan(q[300]).all()
        # The filters saw one frame fewer: the angles barely differ from the clean run's.
        assert np.nanmax(np.abs(q[301:] - clean[301:])) < 2e-3


def _window_estimate(session, corrupt_wrench=None) -> dict:
    """The live path: causal angles frame by frame, then the sliding-window identifier over the last 30 s."""
    from bsp_ros.core.identification.data import wrench_world_yzx
    from bsp_ros.live.online.windowed import WindowConfig, WindowedIdentifier

    frames: dict[int, dict[str, np.ndarray]] = {}
    for name, series in session.markers.items():
        for t, p in zip(series.t_ns, series.position_m, strict=True):
            frames.setdefault(int(t), {})[name] = p
    estimator = CausalJointAngles(3)
    identifier = WindowedIdentifier(3, WindowConfig(window_s=30.0))
    wrench = wrench_world_yzx(session.wrench, session.rotation_world_from_sensor)
    if corrupt_wrench is not None:
        wrench = corrupt_wrench(wrench)
    events = [(int(t), 0, i) for i, t in enumerate(session.wrench.t_ns)] + [(t, 1, -1) for t in sorted(frames)]
    for t, kind, index in sorted(events):
        if kind == 0:
            identifier.add_wrench(t, wrench[index])
        else:
            estimator.update(t, frames[t])
            if estimator.accepted(t):
                identifier.add_joint_state(t, estimator.last_raw_q_rad, estimator.lengths_m)
    return identifier.estimate().document


def test_live_window_estimates_survive_a_glitched_marker_frame_and_wrench_spikes(live_streams) -> None:
    from bsp_ros.core import glitches

    simulated, _, _, _, _ = live_streams
    session = simulated.session
    clean = _window_estimate(session)
    assert clean["quality"]["valid"], clean["quality"]["message"]

    def spikes(wrench: np.ndarray) -> np.ndarray:
        out = wrench.copy()
        out[np.random.default_rng(1).choice(np.arange(4000, 6000), 10, replace=False), 1] = 1000.0
        return out

    for document in (
        _window_estimate(glitches.displace_marker(session, "elbow", 2500, (0.0, 0.67, 0.0))),
        _window_estimate(glitches.displace_marker(session, "hand", 2500, (0.0, 0.0, 0.06))),
        _window_estimate(session, spikes),
    ):
        assert document["quality"]["valid"], document["quality"]["message"]
        for group in ("segments", "joints"):
            for owner, quantities in clean[group].items():
                for key, q in quantities.items():
                    if q["source"] == "data" and q["std"]:
                        got = document[group][owner][key]["value"]
                        assert abs(got - q["value"]) < 3 * q["std"], (owner, key, got, q)
