"""The sample-by-sample filter against scipy's sosfilt on the whole sequence."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from bsp_ros.live.online.streaming_filter import StreamingFilter


@pytest.mark.parametrize("cutoff_hz", [5.0, 0.5])
def test_steps_match_sosfilt_started_in_steady_state(cutoff_hz: float) -> None:
    rng = np.random.default_rng(7)
    sos = signal.butter(2, cutoff_hz, fs=100.0, output="sos")
    x = np.cumsum(rng.normal(size=(400, 3)), axis=0)
    expected, _ = signal.sosfilt(sos, x, axis=0, zi=signal.sosfilt_zi(sos)[:, :, None] * x[0][None, None, :])
    stepper = StreamingFilter(sos)
    got = np.array([stepper.step(row) for row in x])
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9 * np.abs(expected).max())


def test_reset_starts_again_in_steady_state() -> None:
    stepper = StreamingFilter(signal.butter(2, 5.0, fs=100.0, output="sos"))
    for _ in range(50):
        stepper.step(np.array([1.0, -2.0]))
    stepper.reset()
    np.testing.assert_allclose(stepper.step(np.array([3.0, 4.0])), [3.0, 4.0], atol=1e-12)
