"""The live wrench stream's Hampel gate: spikes out, friction's steps and the sensor's noise in."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.identification.robust import hampel_outliers
from bsp_ros.live.online.spike_gate import HALF, SpikeGate


def _stream(seed: int, n: int = 20_000) -> np.ndarray:
    """(n, 3) ``[F_y, F_z, M_x]`` at 1 kHz: a slow swing, a friction-like 3 N step at every reversal (each 2 s) and
    0.05 N / 0.005 Nm of sensor noise."""
    rng = np.random.default_rng(seed)
    t_s = np.arange(n) / 1000.0
    step = 1.5 * np.sign(np.sin(np.pi * t_s / 2.0 + 0.1))
    wrench = np.column_stack((4.0 * np.sin(0.5 * t_s) + step, -20.0 + 2.0 * np.cos(0.5 * t_s) - step, 0.1 * step))
    return wrench + rng.normal(0.0, [0.05, 0.05, 0.005], wrench.shape)


def _verdicts(wrench: np.ndarray) -> tuple[list[int], np.ndarray]:
    gate: SpikeGate[int] = SpikeGate()
    order, spikes = [], np.zeros(len(wrench), dtype=bool)
    for i, w in enumerate(wrench):
        judged = gate.push(w.tolist(), i)
        if judged is not None:
            order.append(judged[0])
            spikes[judged[0]] = judged[1]
    assert gate.spikes == spikes.sum()
    return order, spikes


def test_friction_steps_and_noise_pass_and_each_wrench_is_judged_half_a_window_later_in_order() -> None:
    wrench = _stream(0)
    order, spikes = _verdicts(wrench)
    assert order == list(range(len(wrench) - HALF))  # the newest HALF wait for their later neighbours
    assert not spikes.any()
    # The same stream has its 3 N steps: a gate that tested deviations from the wrenches before each would refuse them.
    assert np.abs(np.diff(wrench[:, 0])).max() > 2.5


def test_the_spikes_bsp_identify_drops_are_the_ones_the_gate_drops() -> None:
    rng = np.random.default_rng(1)
    wrench = _stream(1)
    at = rng.choice(np.arange(100, len(wrench) - 100), 30, replace=False)
    wrench[at, rng.integers(0, 2, at.size)] += rng.choice([-1.0, 1.0], at.size) * rng.uniform(5.0, 1000.0, at.size)
    _, spikes = _verdicts(wrench)
    assert set(np.flatnonzero(spikes)) == set(at.tolist())
    # The offline Hampel test on the recorded stream (the same window and threshold, without the live floor) agrees.
    assert set(np.flatnonzero(hampel_outliers(wrench))) == set(at.tolist())


def test_a_deviation_below_the_floor_is_no_spike_on_a_quantised_sensor() -> None:
    wrench = np.zeros((2_000, 3))
    wrench[1_000, 1] = 0.25  # N: over 8 robust sd of a MAD of 0, under the 0.5 N floor
    wrench[1_500, 1] = 2.0
    _, spikes = _verdicts(wrench)
    assert np.flatnonzero(spikes).tolist() == [1_500]
