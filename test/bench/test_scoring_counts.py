"""bench/scoring.py's Counts: both error rates, the worst |z| and the two-sided tally of seeded estimates whose errors
are known, against a count written out longhand from each estimate's errors."""

from __future__ import annotations

import dataclasses
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

# The benchmarks are scripts, not a package: their directory is put on the path as they run it.
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

import calibration
import scoring

TRUTH = {
    "segments": {"forearm": {"static_moment_kgm": 0.25, "mass_kg": 1.2}, "hand": {"static_moment_kgm": 0.04}},
    "joints": {"elbow": {"coulomb_nm": 0.28}},
}
NAMES = ("static_moment_kgm/forearm", "mass_kg/forearm", "static_moment_kgm/hand", "coulomb_nm/elbow")


def _estimate(z: np.ndarray, std: np.ndarray, valid: bool) -> dict[str, Any]:
    """An estimate whose parameters (in :data:`NAMES` order) sit ``z`` of their ``std`` off the truth."""
    document: dict[str, Any] = {"segments": {}, "joints": {}, "quality": {"valid": valid}}
    for name, z_k, std_k in zip(NAMES, z, std, strict=True):
        key, owner = name.split("/")
        group = "joints" if owner == "elbow" else "segments"
        value = TRUTH[group][owner][key] + z_k * std_k
        document[group].setdefault(owner, {})[key] = {"value": value, "std": std_k, "source": "data"}
    return document


def _draws(seed: int, n: int) -> list[tuple[np.ndarray, np.ndarray, bool]]:
    """``n`` estimates' z (a normal of sd 1.6, so that some pass 3), stds and validity, seeded."""
    rng = np.random.default_rng(seed)
    return [(rng.normal(0.0, 1.6, 4), rng.uniform(0.005, 0.05, 4), bool(rng.random() < 0.7)) for _ in range(n)]


def test_counts_match_a_longhand_count_of_known_errors() -> None:
    draws = _draws(7, 300)
    counts = scoring.Counts()
    for z, std, valid in draws:
        run = counts.score(_estimate(z, std, valid), TRUTH)
        assert run.max_z == pytest.approx(np.abs(z).max())
        assert run.worst == NAMES[int(np.argmax(np.abs(z)))]
    worst = np.array([np.abs(z).max() for z, _, _ in draws])
    valid_mask = np.array([v for _, _, v in draws])
    assert (counts.runs, counts.valid, counts.failed) == (300, valid_mask.sum(), 0)
    assert counts.valid_wrong == np.sum(valid_mask & (worst > 3.0)) > 0
    assert counts.invalid_right == np.sum(~valid_mask & (worst <= 3.0)) > 0
    assert counts.worst_z == pytest.approx(worst.max())
    # The two-sided tally holds the valid estimates' z alone, signed.
    signed = np.concatenate([z for z, _, v in draws if v])
    assert dataclasses.astuple(counts.two_sided.calibration()) == pytest.approx(
        dataclasses.astuple(calibration.calibration(signed))
    )
    assert sorted(counts.two_sided.z) == pytest.approx(sorted(signed))


def test_pooled_rows_count_as_one_row() -> None:
    draws = _draws(8, 120)
    whole, rows = scoring.Counts(), [scoring.Counts(), scoring.Counts(), scoring.Counts()]
    for k, (z, std, valid) in enumerate(draws):
        whole.score(_estimate(z, std, valid), TRUTH)
        rows[k % 3].score(_estimate(z, std, valid), TRUTH)
    rows[1].count_failure()
    whole.count_failure()
    pooled = scoring.Counts()
    for row in rows:
        pooled.pool(row)
    assert pooled.counts_json() == whole.counts_json()
    assert (pooled.failed, pooled.worst_z, pooled.worst_param) == (1, whole.worst_z, whole.worst_param)
    assert dataclasses.astuple(pooled.two_sided.calibration()) == pytest.approx(
        dataclasses.astuple(whole.two_sided.calibration())
    )


def test_an_estimate_without_a_scored_parameter_is_ok_unless_the_row_counts_it_right() -> None:
    unscored = {"segments": {}, "joints": {}, "quality": {"valid": False}}
    counts = scoring.Counts()
    run = counts.score(unscored, TRUTH)
    assert math.isnan(run.max_z) and run.worst == "" and run.verdict == "ok"
    assert (counts.runs, counts.invalid_right, counts.worst_param) == (1, 0, "")

    class Vacuous(scoring.Counts):
        UNSCORED_INVALID_RIGHT = True

    vacuous = Vacuous()
    vacuous.score(unscored, TRUTH)
    vacuous.score({**unscored, "quality": {"valid": True}}, TRUTH)
    assert (vacuous.runs, vacuous.invalid_right, vacuous.valid_wrong) == (2, 1, 0)


def test_a_zero_std_off_the_truth_is_infinitely_wrong() -> None:
    z, std = np.array([0.5, 0.2, 0.1, 0.0]), np.array([0.01, 0.1, 0.01, 0.0])
    document = _estimate(z, std, True)
    document["joints"]["elbow"]["coulomb_nm"]["value"] = 0.3  # 0.02 Nm off with a std of 0
    counts = scoring.Counts()
    run = counts.score(document, TRUTH)
    assert run.max_z == math.inf and run.worst == "coulomb_nm/elbow" and run.wrong
    assert counts.valid_wrong == 1 and counts.worst_z == math.inf
