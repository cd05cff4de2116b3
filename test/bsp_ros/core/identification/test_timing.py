"""Stream timing: a wrench stream 20 ms late and filtered (1.5 ms moving average) is found and compensated."""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np
import pytest

from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.identification.timing import (
    DelayProblem,
    compensate_wrench_delay,
    delay_problem,
    estimate_wrench_delay,
    linear_rss,
    parameter_timing,
)
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.core.simulation import CellSimulator, SessionTruth, human_arm_cell, simulate_cell
from bsp_ros.core.streams import Session, WrenchSeries
from bsp_ros.errors import InputError

TRANSPORT_S = 0.020
FILTER_S = 0.0015  # a moving average over 1.5 ms: a group delay of half of it
TRUE_DELAY_S = TRANSPORT_S + FILTER_S / 2


def delayed_session(
    seed: int, delay_s: float, filter_s: float, duration_s: float = 60.0
) -> tuple[Session, SessionTruth]:
    """A simulated session whose wrench stamped ``t`` is the sensor's moving average of the true wrench over
    ``[t - delay_s - filter_s, t - delay_s]`` (sampled every 0.25 ms), with the simulator's noise."""
    sim = CellSimulator(human_arm_cell(duration_s=duration_s, seed=seed))
    t_ns = sim.wrench_stamps_ns()
    noisy = sim.sample_wrench(t_ns)  # noise at the stamps; its noise-free part is replaced below
    t_s = sim.seconds_since_start(t_ns)
    offsets = np.linspace(0.0, filter_s, round(filter_s / 0.00025) + 1)
    late = np.mean([sim.wrench_world(t_s - delay_s - o) for o in offsets], axis=0) - sim.wrench_world(t_s)
    r = sim.rotation_world_from_sensor
    force = np.column_stack((np.zeros(t_ns.size), late[:, 0], late[:, 1])) @ r  # row form of R^T v
    torque = np.column_stack((late[:, 2], np.zeros(t_ns.size), np.zeros(t_ns.size))) @ r
    wrench = WrenchSeries(t_ns, noisy.force_n + force, noisy.torque_nm + torque, noisy.frame_id)
    return Session(wrench, sim.sample_markers(sim.marker_stamps_ns()), np.array(r)), sim.truth


@pytest.fixture(scope="module")
def late() -> tuple[Session, SessionTruth]:
    return delayed_session(seed=3, delay_s=TRANSPORT_S, filter_s=FILTER_S)


def _z_scores(document: dict, truth: SessionTruth) -> list[float]:
    out = []
    for segment, beta in zip(("upper_arm", "forearm", "hand"), truth.static_moments_kgm, strict=True):
        q = document["segments"][segment]["static_moment_kgm"]
        out.append((q["value"] - beta) / q["std"])
    for joint, c in zip(("shoulder", "elbow", "wrist"), truth.passive.coulomb_nm, strict=True):
        q = document["joints"][joint]["coulomb_nm"]
        out.append((q["value"] - c) / q["std"])
    return out


def test_the_delay_of_a_late_filtered_wrench_is_found_within_its_std_cheaply(
    late: tuple[Session, SessionTruth],
) -> None:
    problem = delay_problem(late[0])
    started = time.perf_counter()
    delay = estimate_wrench_delay(problem)
    elapsed_s = time.perf_counter() - started
    assert delay.source == "estimated" and delay.delay_s == delay.estimate_s
    assert abs(delay.delay_s - TRUE_DELAY_S) <= 2.0 * delay.std_s, (delay.delay_s, delay.std_s)
    # Resolved to a few milliseconds from 60 s: the profile fits marker offsets, off-axis moments and springs beside
    # gravity and friction, whose share of the misfit would otherwise read as a delay.
    assert 0.0003 < delay.std_s < 0.006
    # Two profiles (gravity and friction alone, and with the nuisances), each a grid of linear fits, 3 to refine and 4
    # for the std.
    assert delay.n_fits <= 40 and elapsed_s < 2.0


def test_compensated_the_static_moments_and_coulomb_amplitudes_return_within_3_std(
    late: tuple[Session, SessionTruth],
) -> None:
    session, truth = late
    # The simulated markers sit on the joint centres: no placement uncertainty to hide the delay's bias in.
    document = identify_session(session, IdentifyOptions(marker_placement_sd_m=0.0))
    timing = document["quality"]["timing"]
    assert (
        timing["source"] == "estimated"
        and abs(timing["wrench_delay_s"] - TRUE_DELAY_S) < 3 * timing["wrench_delay_std_s"]
    )
    assert document["quality"]["valid"], document["quality"]["message"]
    assert max(abs(z) for z in _z_scores(document, truth)) <= 3.0
    # Left uncompensated (the cell says 0), the late wrench biases the shoulder's friction far beyond its std.
    ignored = identify_session(session, IdentifyOptions(wrench_delay_s=0.0, marker_placement_sd_m=0.0))
    assert ignored["quality"]["timing"] == {"wrench_delay_s": 0.0, "wrench_delay_std_s": 0.0, "source": "parameter"}
    assert max(abs(z) for z in _z_scores(ignored, truth)) > 5.0


def test_a_known_delay_is_applied_as_given(late: tuple[Session, SessionTruth]) -> None:
    session, truth = late
    shifted, timing = compensate_wrench_delay(session, TRUE_DELAY_S)
    assert timing.quality() == {"wrench_delay_s": TRUE_DELAY_S, "wrench_delay_std_s": 0.0, "source": "parameter"}
    np.testing.assert_array_equal(shifted.wrench.t_ns, session.wrench.t_ns - round(TRUE_DELAY_S * 1e9))
    document = identify_session(session, IdentifyOptions(wrench_delay_s=TRUE_DELAY_S))
    assert document["quality"]["valid"] and max(abs(z) for z in _z_scores(document, truth)) <= 3.0
    with pytest.raises(InputError, match="wrench_delay_s"):
        compensate_wrench_delay(session, math.inf)


def test_without_a_delay_nothing_is_compensated() -> None:
    session, _ = delayed_session(seed=4, delay_s=0.0, filter_s=0.0)
    delay = estimate_wrench_delay(session)
    assert abs(delay.estimate_s) <= 3.0 * delay.estimate_std_s
    assert delay.source == "none" and delay.delay_s == 0.0
    assert delay.quality()["source"] == "none" and delay.quality()["estimated_delay_s"] == delay.estimate_s
    assert parameter_timing(None)["source"] == "none" and parameter_timing(0.01)["source"] == "parameter"


@pytest.mark.parametrize("seed", [1, 2])
def test_friction_that_turns_smoothly_is_not_read_as_a_delay(seed: int) -> None:
    """Coulomb friction that changes direction over 5 mrad/s (a tanh), no delay: its shape at the reversals once
    read as a delay of -89 +- 18 ms that both profiles resolved and the estimate applied (the shoulder's Coulomb
    amplitude 7.5 % low, 3.1 std)."""
    spec = human_arm_cell(seed=seed, duration_s=120.0)
    spec = dataclasses.replace(spec, passive=dataclasses.replace(spec.passive, friction_transition_rad_s=0.005))
    delay = estimate_wrench_delay(simulate_cell(spec).session)
    assert delay.source == "none" and delay.delay_s == 0.0
    assert abs(delay.estimate_s) < 2.0 * delay.estimate_std_s, (delay.estimate_s, delay.estimate_std_s)


def test_the_fit_is_pluggable(late: tuple[Session, SessionTruth]) -> None:
    problem = delay_problem(late[0])
    calls: list[int] = []

    def counting(reference: DelayProblem):  # the caller's model: here the default one, counted
        keep = reference.data(-0.12)[1] & reference.data(0.12)[1] & reference.data(0.0)[1]
        inner = linear_rss(reference.data(0.0, keep)[0])

        def fit_rss(data) -> float:
            calls.append(data.t_ns.size)
            return inner(data)

        return fit_rss

    plugged = estimate_wrench_delay(problem, counting(problem))
    default = estimate_wrench_delay(problem)
    assert len(calls) == plugged.n_fits - 4 and len(set(calls)) == 1  # the same samples at every delay
    assert plugged.delay_s == pytest.approx(default.delay_s, abs=1e-9)


def test_a_delay_beyond_the_search_is_not_compensated() -> None:
    session, _ = delayed_session(seed=5, delay_s=0.3, filter_s=0.0, duration_s=40.0)
    delay = estimate_wrench_delay(session)
    assert delay.source == "none" and delay.delay_s == 0.0
    assert "beyond the searched" in delay.warnings[0]
    # The estimate says so as a finding of its own (a note: the estimate stands, uncompensated).
    quality = identify_session(session)["quality"]
    timing = [f for f in findings_of(quality) if f.code is FindingCode.TIMING_NOTE]
    assert [f.text for f in timing] == delay.warnings and timing[0].text in quality["warnings"]


@pytest.mark.parametrize("minimum_s", [-0.13, -0.1, -0.047, 0.0, 0.031, 0.09, 0.2])
def test_the_downhill_walk_finds_the_grids_minimum_with_its_neighbours(minimum_s: float) -> None:
    from bsp_ros.core.identification.timing import _descend

    grid = np.arange(-0.1, 0.1 + 0.01, 0.02)
    calls: list[float] = []

    def misfit(delay_s: float) -> float:
        calls.append(delay_s)
        return (delay_s - minimum_s) ** 2 + 0.3 * abs(delay_s - minimum_s) ** 3

    walked = _descend(grid, misfit)
    full = np.array([misfit(d) for d in grid])
    best = int(np.argmin(full))
    assert int(np.nanargmin(walked)) == best
    around = slice(max(best - 1, 0), best + 2)
    np.testing.assert_array_equal(walked[around], full[around])
    assert len(calls) - grid.size < grid.size  # fewer fits than the whole grid
