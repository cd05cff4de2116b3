"""The precision signal: it comes once every targeted parameter stayed within its target for the hold, then stays for
the session; the inputs stopped for the session gap clear it. Checked on hand-made estimates (the arithmetic is the
truth) and on the windowed estimates of a simulated session (its parameters known)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pytest
from live_inputs import WindowFeed, orientation

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.pipeline import IdentifyOptions
from bsp_ros.errors import InputError
from bsp_ros.live.online.identifier_settings import IdentifierSettings
from bsp_ros.live.online.precision import (
    ParameterPrecision,
    PrecisionState,
    PrecisionTarget,
    PrecisionTracker,
)
from bsp_ros.live.online.windowed import WindowConfig, WindowedIdentifier

S = 1_000_000_000  # ns per second
SEGMENTS = ("upper_arm", "forearm")


def _estimate(relative: Mapping[str, float | None], valid: bool = True, verdict: FindingCode | None = None) -> Estimate:
    """An estimate whose static moments are 1 kg m with the given relative std (None: no std)."""
    segments = {name: {"static_moment_kgm": {"value": 1.0, "std": r, "source": "data"}} for name, r in relative.items()}
    findings = [] if verdict is None else [Finding(code=verdict, values={"what": "wrench", "silent_s": 1.0}).to_json()]
    quality = {"valid": valid and verdict is None, "message": "", "findings": findings}
    return Estimate.from_json({"method": "joint", "segments": segments, "joints": {}, "quality": quality})


def _tracker(hold_s: float = 2.0, percent: float = 5.0) -> PrecisionTracker:
    return PrecisionTracker(PrecisionTarget.static_moments(percent, SEGMENTS, hold_s=hold_s))


WITHIN = {"upper_arm": 0.02, "forearm": 0.04}
ABOVE = {"upper_arm": 0.02, "forearm": 0.07}


def test_the_signal_comes_only_after_every_parameter_stayed_within_its_target_for_the_hold() -> None:
    tracker = _tracker(hold_s=2.0)
    states = [tracker.update(_estimate(WITHIN), t * S // 5) for t in range(16)]  # 0..3 s at 5 Hz
    reached = [s.reached for s in states]
    assert reached.index(True) == 10  # 2.0 s after the first estimate within
    assert states[10].reached_after_s == pytest.approx(2.0)
    assert states[9].within_s == pytest.approx(1.8) and not states[9].reached


def test_a_window_above_target_before_the_hold_restarts_it() -> None:
    tracker = _tracker(hold_s=2.0)
    for t in range(8):
        tracker.update(_estimate(WITHIN), t * S // 5)  # 1.4 s within
    state = tracker.update(_estimate(ABOVE), 8 * S // 5)
    assert state.within_s is None and not state.reached
    assert state.worst is not None and state.worst.owner == "forearm" and state.worst.ratio == pytest.approx(1.4)
    states = [tracker.update(_estimate(WITHIN), t * S // 5) for t in range(9, 25)]
    assert [s.reached for s in states].index(True) == 10  # 2 s from t = 1.8 s: at 3.8 s
    assert states[10].reached_after_s == pytest.approx(3.8)


def test_once_reached_it_stays_through_wider_and_invalid_estimates_and_short_input_gaps() -> None:
    tracker = _tracker(hold_s=0.0)
    assert tracker.update(_estimate(WITHIN), 0).reached
    assert tracker.update(_estimate(ABOVE), S).reached
    assert tracker.update(_estimate(WITHIN, valid=False), 2 * S).reached
    for t in range(3, 7):  # 4 s of a stopped wrench stream: shorter than the 5 s session gap
        state = tracker.update(_estimate({}, verdict=FindingCode.INPUT_STALE), t * S)
        assert state.reached and state.within_s is None
    assert tracker.update(_estimate(ABOVE), 7 * S).reached


def test_inputs_stopped_for_the_session_gap_clear_it_and_a_new_session_starts_over() -> None:
    tracker = _tracker(hold_s=1.0)
    tracker.update(_estimate(WITHIN), 0)
    assert tracker.update(_estimate(WITHIN), S).reached
    for t in range(2, 8):
        state = tracker.update(_estimate({}, verdict=FindingCode.INPUT_STALE), t * S)
    assert not state.reached  # 5 s stopped (2 .. 7 s)
    tracker.update(_estimate(WITHIN), 10 * S)
    state = tracker.update(_estimate(WITHIN), 11 * S)
    assert state.reached and state.reached_after_s == pytest.approx(1.0)  # timed from the new session's start


def test_a_parameter_without_a_std_or_missing_is_not_within() -> None:
    tracker = _tracker(hold_s=0.0)
    state = tracker.update(_estimate({"upper_arm": 0.01, "forearm": None}), 0)
    assert not state.reached
    forearm = next(p for p in state.parameters if p.owner == "forearm")
    assert forearm.relative_std is None and not forearm.within and math.isinf(forearm.ratio)
    assert not tracker.update(_estimate({"upper_arm": 0.01}), S).reached


def test_the_state_round_trips_through_its_json_block() -> None:
    tracker = _tracker(hold_s=0.0)
    state = tracker.update(_estimate(WITHIN), 0)
    block = state.to_json()
    assert block["reached"] is True and block["hold_s"] == 0.0
    assert block["parameters"][1] == {
        "owner": "forearm",
        "quantity": "static_moment_kgm",
        "relative_std_percent": pytest.approx(4.0),
        "target_percent": pytest.approx(5.0),
        "within": True,
    }
    again = PrecisionState.from_json(block)
    assert again.reached and again.parameters[1].relative_std == pytest.approx(0.04)
    assert isinstance(again.worst, ParameterPrecision) and again.worst.owner == "forearm"


@pytest.mark.parametrize(
    ("limits", "hold_s", "gap_s"),
    [
        ({}, 1.0, 5.0),
        ({("forearm", "static_moment_kgm"): 0.0}, 1.0, 5.0),
        ({("forearm", "static_moment_kgm"): math.nan}, 1.0, 5.0),
        ({("forearm", "static_moment_kgm"): 0.05}, -1.0, 5.0),
        ({("forearm", "static_moment_kgm"): 0.05}, 1.0, 0.0),
    ],
)
def test_a_target_refuses_what_cannot_be_a_target(
    limits: dict[tuple[str, str], float], hold_s: float, gap_s: float
) -> None:
    with pytest.raises(ValueError):
        PrecisionTarget(relative_std=limits, hold_s=hold_s, session_gap_s=gap_s)


def test_on_a_simulated_session_the_signal_waits_for_valid_windows_then_stays_and_holds_the_truth(
    live_streams: Any,
) -> None:
    """The windowed estimates of a 60 s simulated session (untared: the sensor zero's 1 N keeps the std near 4 % on
    the upper arm's static moment and 11 % on the forearm's), one a second, against targets of 5 % and 12 %. The first
    windows are invalid (a joint has moved one way only) though the upper arm's std is already below 5 %: the signal
    waits for valid windows, comes the hold after the first, stays, and those estimates hold the simulated truth
    within 3 of their std."""
    simulated, stamps, wrench, _, raw = live_streams
    identifier = WindowedIdentifier(3, WindowConfig(30.0, 60.0, IdentifyOptions()))
    feed = WindowFeed(identifier, stamps, wrench, raw)
    limits = {("upper_arm", "static_moment_kgm"): 0.05, ("forearm", "static_moment_kgm"): 0.12}
    tracker = PrecisionTracker(PrecisionTarget(relative_std=limits, hold_s=3.0))
    truth = simulated.truth.to_dict()["segments"]
    start = int(stamps[0])
    estimates, states = [], []
    for t in range(start + 5 * S, int(stamps[-1]), S):
        feed.until(t)
        estimate = Estimate.from_json(identifier.estimate(t, orientation(simulated)).document)
        estimates.append(estimate)
        states.append(tracker.update(estimate, t))
    first_valid = next(i for i, e in enumerate(estimates) if e.valid)
    early = [s.parameters[0] for s, e in zip(states, estimates, strict=True) if not e.valid and s.parameters[0].within]
    assert early, "an invalid window with the upper arm's std below target (what the signal must not come on)"
    reached = [s.reached for s in states]
    first = reached.index(True)
    assert first == first_valid + 3 and all(reached[first:]), reached
    assert states[first].reached_after_s == pytest.approx(first)  # from the session's first estimate
    for estimate in estimates[first:]:
        assert estimate.valid
        for owner, key in limits:
            q = estimate.quantity(key, owner)
            assert q is not None and q.value is not None and q.std is not None
            assert abs(q.value - truth[owner][key]) < 3 * q.std
    assert all(np.isfinite(s.worst.ratio) for s in states[first:])  # type: ignore[union-attr]


def test_the_identifier_parameters_make_the_target_or_leave_it_off() -> None:
    assert IdentifierSettings.from_parameters({}).precision_target is None  # default off
    settings = IdentifierSettings.from_parameters({"target_std_percent": 4.0, "precision_hold_s": 2.5})
    target = settings.precision_target
    assert target is not None and target.hold_s == 2.5
    assert target.relative_std == {("upper_arm", "static_moment_kgm"): 0.04, ("forearm", "static_moment_kgm"): 0.04}
    with_hand = IdentifierSettings.from_parameters({"target_std_percent": 4.0, "target_segments": ["hand"]})
    assert with_hand.precision_target is not None
    assert list(with_hand.precision_target.relative_std) == [("hand", "static_moment_kgm")]


@pytest.mark.parametrize("segments", [["wrist"], [], ["hand"]])
def test_target_segments_outside_the_chain_are_refused_naming_the_parameter(segments: list[str]) -> None:
    with pytest.raises(InputError, match="target_segments"):
        IdentifierSettings.from_parameters({"target_std_percent": 4.0, "target_segments": segments, "n_segments": 2})
