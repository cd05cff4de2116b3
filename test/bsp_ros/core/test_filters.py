"""The numpy Butterworth design and zero-phase filter against scipy.signal (the implementation they replace)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy import signal

from bsp_ros.core.filters import butter_lowpass_sos, zero_phase_lowpass

CASES = [
    (order, cutoff_hz, rate_hz)
    for order in (1, 2, 3, 4, 6)
    for cutoff_hz, rate_hz in ((0.5, 100.0), (5.0, 50.0), (1.0, 1000.0), (20.0, 50.0))
]


@pytest.mark.parametrize(("order", "cutoff_hz", "rate_hz"), CASES)
def test_the_filter_is_scipys(order: int, cutoff_hz: float, rate_hz: float) -> None:
    expected = signal.butter(order, cutoff_hz, fs=rate_hz, output="sos")
    sos = butter_lowpass_sos(order, cutoff_hz, rate_hz)
    if order % 2 == 0:  # odd orders may pair the single zero with another section: compare responses
        np.testing.assert_allclose(sos, expected, rtol=1e-12, atol=1e-15)
    _, response = signal.sosfreqz(sos, worN=256, fs=rate_hz)
    _, reference = signal.sosfreqz(expected, worN=256, fs=rate_hz)
    np.testing.assert_allclose(response, reference, rtol=1e-9, atol=1e-12)
    rng = np.random.default_rng(order)
    values = np.cumsum(rng.normal(size=(2000, 3)), axis=0)  # a random walk: slopes at the ends matter
    padlen = min(values.shape[0] - 1, int(3.0 * rate_hz / cutoff_hz))
    ours = zero_phase_lowpass(values, sos, padlen)
    theirs = signal.sosfiltfilt(expected, values, axis=0, padtype="odd", padlen=padlen)
    # Rounding only: a 6th order at 1/1000 of the rate has poles within 1e-2 of 1 and loses a few more digits (the
    # block states' prefix scan multiplies powers of the block's decay, ~2e-11 of the signal there, 1e-14 elsewhere).
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-9 * np.abs(theirs).max())
    one = zero_phase_lowpass(values[:, 0], sos, 0)
    np.testing.assert_allclose(
        one, signal.sosfiltfilt(expected, values[:, 0], padtype=None), atol=1e-10 * np.abs(theirs).max()
    )


def test_a_bad_design_is_refused() -> None:
    for order, cutoff_hz in ((0, 1.0), (2, 0.0), (2, 50.0)):
        with pytest.raises(ValueError, match="Butterworth"):
            butter_lowpass_sos(order, cutoff_hz, 100.0)


def test_bsp_identify_imports_no_scipy(tmp_path) -> None:
    # scipy.signal and scipy.stats cost `bsp identify` about 0.4 s of import, scipy.linalg 0.17 s, scipy.optimize
    # 0.13 s (issue 23; bench/README): the whole identification, model checks included, runs without them.
    from bsp_ros.bag import write_session_bag
    from bsp_ros.core import simulation as sim

    simulated = sim.simulate_cell(sim.human_arm_cell(seed=4, duration_s=40.0))
    write_session_bag(tmp_path / "bag", simulated.session, simulated.truth.to_dict())
    code = (
        "import sys; from bsp_ros.cli import main; "
        f"code = main(['identify', {str(tmp_path / 'bag')!r}, '--format', 'none']); "
        "print(code, sorted(m for m in sys.modules if m == 'scipy' or m.startswith('scipy.')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "0 []"


def test_the_sections_run_as_scipys_sosfilt_across_block_boundaries() -> None:
    from bsp_ros.core.filters import sosfilt

    rng = np.random.default_rng(8)
    sos = np.array(butter_lowpass_sos(4, 2.0, 100.0))
    for n in (2, 17, 63, 64, 65, 1000):
        values = np.cumsum(rng.normal(size=(n, 3)), axis=0)
        states = rng.normal(size=(2, 2, 3))
        expected = signal.sosfilt(sos, values, axis=0, zi=states)[0]
        np.testing.assert_allclose(sosfilt(sos, values, states), expected, atol=1e-12 * np.abs(expected).max())
