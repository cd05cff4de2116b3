"""The benchmarks' calibration and sharpness metrics (bench/calibration.py) against draws of known spread."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

# The benchmarks are scripts, not a package: their directory is put on the path as they run it.
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

import calibration
import scoring

N = 20_000  # draws: the shares' sampling error is below 0.4 percentage points (1 sd)


def _draws(std: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Errors of an estimator whose true spread is 1, reported with ``std`` (N draws, seeded)."""
    errors = np.random.default_rng(seed).normal(0.0, 1.0, N)
    return errors, np.full(N, std)


def test_honest_std_gives_z_rms_one_and_normal_shares():
    errors, stds = _draws(1.0, 0)
    c = calibration.calibration(errors / stds)
    assert c.count == N
    assert c.z_rms == pytest.approx(1.0, abs=0.02)
    assert c.within_1 == pytest.approx(calibration.HONEST_WITHIN_1, abs=0.015)
    assert c.within_2 == pytest.approx(calibration.HONEST_WITHIN_2, abs=0.01)
    assert c.within_3 == pytest.approx(0.9973, abs=0.003)
    assert calibration.sharpness(errors, stds) == pytest.approx(1.0, abs=0.02)


def test_std_ten_times_too_wide_gives_z_rms_tenth_and_sharpness_ten():
    errors, stds = _draws(10.0, 1)
    c = calibration.calibration(errors / stds)
    assert c.z_rms == pytest.approx(0.1, abs=0.003)
    assert c.within_1 == 1.0 and c.within_2 == 1.0  # passes every one-sided check
    assert calibration.sharpness(errors, stds) == pytest.approx(10.0, rel=0.02)


def test_std_too_narrow_gives_z_rms_above_one_and_sharpness_below_one():
    errors, stds = _draws(0.5, 2)
    c = calibration.calibration(errors / stds)
    assert c.z_rms == pytest.approx(2.0, rel=0.02)
    assert c.within_1 == pytest.approx(0.3829, abs=0.015)  # P(|x| <= 0.5) of a standard normal
    assert calibration.sharpness(errors, stds) == pytest.approx(0.5, rel=0.02)


def test_sign_of_z_does_not_change_calibration_and_nan_is_left_out():
    z = np.array([-2.0, 2.0, math.nan, 0.5])
    c = calibration.calibration(z)
    assert c.count == 3
    assert c.z_rms == pytest.approx(math.sqrt((4 + 4 + 0.25) / 3))
    assert c.within_1 == pytest.approx(1 / 3)
    assert c.within_2 == pytest.approx(1.0)


def test_zero_std_is_infinite_unless_exact():
    z = calibration.z_values({"a/x": (0.1, 0.0), "b/x": (-0.1, 0.0), "c/x": (0.0, 0.0)})
    assert z == {"a/x": math.inf, "b/x": -math.inf, "c/x": 0.0}
    assert calibration.calibration(list(z.values())).z_rms == math.inf


def test_empty_and_degenerate_inputs_are_nan():
    assert calibration.calibration([]).count == 0
    assert math.isnan(calibration.calibration([]).z_rms)
    assert math.isnan(calibration.sharpness([0.1], [0.1]))  # one session: no spread to compare with
    assert math.isnan(calibration.sharpness([0.0, 0.0], [0.1, 0.1]))  # exact every time: no scale
    with pytest.raises(ValueError):
        calibration.sharpness([0.1, 0.2], [0.1])


def test_sharpness_by_kind_summarizes_each_kind_and_ignores_others():
    rng = np.random.default_rng(3)
    samples = {}
    # Static moments honest, Coulomb amplitudes 10x too wide, masses 3x too wide for one segment only.
    for owner, mass_factor in (("upper_arm", 3.0), ("forearm", 1.0), ("hand", 1.0)):
        e = rng.normal(0.0, 0.02, 4000)
        samples[f"static_moment_kgm/{owner}"] = [(x, 0.02) for x in e]
        samples[f"mass_kg/{owner}"] = [(x, 0.02 * mass_factor) for x in e]
        samples[f"length_m/{owner}"] = [(x, 1.0) for x in e]
    for joint in ("shoulder", "elbow", "wrist"):
        samples[f"coulomb_nm/{joint}"] = [(x, 0.1) for x in rng.normal(0.0, 0.01, 4000)]
    kinds = calibration.sharpness_by_kind(samples)
    assert list(kinds) == ["static moments", "Coulomb amplitudes", "masses"]
    assert kinds["static moments"].count == 3
    assert kinds["static moments"].median == pytest.approx(1.0, rel=0.05)
    assert kinds["Coulomb amplitudes"].median == pytest.approx(10.0, rel=0.05)
    assert kinds["masses"].median == pytest.approx(1.0, rel=0.05)
    assert kinds["masses"].high == pytest.approx(3.0, rel=0.05)
    assert kinds["masses"].low == pytest.approx(1.0, rel=0.05)


def test_tally_counts_only_valid_estimates_and_pools_rows():
    rng = np.random.default_rng(4)
    rows = [calibration.Tally(), calibration.Tally()]
    for k in range(400):
        residuals = {"static_moment_kgm/forearm": (float(rng.normal(0.0, 0.03)), 0.03)}
        rows[k % 2].add(residuals, valid=True)
        rows[k % 2].add({"static_moment_kgm/forearm": (5.0, 0.03)}, valid=False)  # ignored
    total = calibration.Tally()
    for row in rows:
        total.extend(row)
    assert total.calibration().count == 400
    assert total.calibration().z_rms == pytest.approx(1.0, abs=0.1)
    assert total.sharpness()["static moments"].median == pytest.approx(1.0, abs=0.1)
    assert total.sharpness()["masses"].count == 0
    line = calibration.summary_line("pooled", total)
    assert "z RMS" in line and "static moments" in line
    assert len(calibration.calibration_columns(total.calibration())) == len(calibration.calibration_header())
    assert len(calibration.sharpness_columns(total.sharpness())) == len(calibration.sharpness_header())


def test_residuals_score_data_sourced_parameters_with_sign():
    document = {
        "segments": {
            "forearm": {
                "static_moment_kgm": {"value": 0.30, "std": 0.01, "source": "data"},
                "mass_kg": {"value": 1.10, "std": 0.2, "source": "data+prior"},
                "inertia_kgm2": {"value": 0.05, "std": 0.01, "source": "prior"},
            }
        },
        "joints": {"elbow": {"coulomb_nm": {"value": 0.25, "std": None, "source": "data"}}},
    }
    truth = {
        "segments": {"forearm": {"static_moment_kgm": 0.28, "mass_kg": 1.2, "inertia_kgm2": 0.03}},
        "joints": {"elbow": {"coulomb_nm": 0.28}},
    }
    r = scoring.residuals(document, truth)
    assert set(r) == {"static_moment_kgm/forearm", "mass_kg/forearm", "coulomb_nm/elbow"}
    assert r["static_moment_kgm/forearm"] == pytest.approx((0.02, 0.01))
    assert r["mass_kg/forearm"] == pytest.approx((-0.1, 0.2))
    assert r["coulomb_nm/elbow"] == pytest.approx((-0.03, 0.0))
    z = scoring.z_scores(document, truth)
    assert z["static_moment_kgm/forearm"] == pytest.approx(2.0)
    assert z["mass_kg/forearm"] == pytest.approx(0.5)
    assert z["coulomb_nm/elbow"] == math.inf
