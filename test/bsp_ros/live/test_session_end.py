"""SessionEndDetector: which live estimate ends up stored, and when (no middleware, no clocks)."""

from __future__ import annotations

import copy
from typing import Any

import pytest
from invalid_estimates import NOT_IDENTIFIED, ONE_WAY_ELBOW, POOR, WAITING, invalid

from bsp_ros.live.session_end import SessionEndDetector

S = 1_000_000_000  # ns per s
T0 = 1_700_000_000 * S


def _valid(value: float, start_ns: int = T0, end_ns: int = T0 + 30 * S) -> dict[str, Any]:
    return {
        "schema": "bsp_ros/core/estimate/1",
        "segments": {"forearm": {"static_moment_kgm": {"value": value, "std": 1e-4, "source": "data"}}},
        "joints": {},
        "quality": {"valid": True, "message": "identified", "level": "ok"},
        "session": {"start_time_ns": start_ns, "end_time_ns": end_ns},
    }


_invalid = invalid


def _feed(detector: SessionEndDetector, documents: list[Any], t_ns: int, period_ns: int = S // 5) -> int:
    """Feed documents every ``period_ns`` from ``t_ns``; return the time of the last one."""
    for k, document in enumerate(documents):
        detector.on_estimate(document, t_ns + k * period_ns)
    return t_ns + (len(documents) - 1) * period_ns


def test_defaults() -> None:
    detector = SessionEndDetector()
    assert detector.end_timeout_s == 5.0
    assert detector.due(T0) is None
    assert detector.due(T0, end_requested=True) is None


def test_silence_hands_out_the_last_valid_estimate_once_after_the_timeout() -> None:
    detector = SessionEndDetector(end_timeout_s=1.0)
    documents = [
        _invalid(WAITING),
        _valid(1.0),
        _invalid(POOR),
        _valid(2.0),
        _invalid(ONE_WAY_ELBOW),
    ]
    last = _feed(detector, documents, T0)
    assert detector.due(last) is None
    assert detector.due(last + S) is None  # exactly the timeout: not yet
    stored = detector.due(last + S + 1)
    assert stored is documents[3]  # the last valid one, though an invalid one came after it
    assert detector.due(last + S + 1) is None
    assert detector.due(last + 100 * S) is None
    assert detector.due(last + 100 * S, end_requested=True) is None


def test_the_timeout_counts_from_the_last_estimate_built_on_live_input() -> None:
    detector = SessionEndDetector(end_timeout_s=1.0)
    detector.on_estimate(_valid(1.0), T0)
    # 4 s of invalid estimates on live but poor data (the arm held still): the session goes on.
    last = _feed(detector, [_invalid(NOT_IDENTIFIED)] * 20, T0 + S // 5)
    for t in range(T0, last + 1, S // 10):
        assert detector.due(t) is None
    assert detector.due(last + S + 1) == _valid(1.0)


def test_stale_input_estimates_count_as_silence_so_stopped_streams_end_the_session() -> None:
    detector = SessionEndDetector(end_timeout_s=1.0)
    detector.on_estimate(_valid(1.0), T0)
    _feed(detector, [_invalid()] * 20, T0 + S // 5)  # the identifier reports its inputs stale, 5 per s
    assert detector.due(T0 + S + 1) == _valid(1.0)


def test_an_end_request_hands_it_out_at_once() -> None:
    detector = SessionEndDetector(end_timeout_s=1000.0)
    detector.on_estimate(_valid(1.0), T0)
    assert detector.due(T0 + S) is None
    assert detector.due(T0 + S, end_requested=True) == _valid(1.0)
    assert detector.due(T0 + S, end_requested=True) is None


def test_invalid_estimates_alone_are_never_stored() -> None:
    detector = SessionEndDetector(end_timeout_s=1.0)
    last = _feed(detector, [_invalid(WAITING), _invalid(POOR), _invalid()], T0)
    assert detector.due(last + 10 * S) is None
    assert detector.due(last + 10 * S, end_requested=True) is None


@pytest.mark.parametrize("valid", [False, None, 0, ""])
def test_only_a_true_valid_flag_counts(valid: Any) -> None:
    detector = SessionEndDetector(end_timeout_s=1.0)
    document = _valid(1.0)
    document["quality"]["valid"] = valid
    detector.on_estimate(document, T0)
    assert detector.due(T0 + 10 * S, end_requested=True) is None


@pytest.mark.parametrize(
    "document",
    [[1, 2], 3, "text", None, {}, {"quality": None}, {"quality": [True]}, {"quality": {}}, {"quality": "valid"}],
)
def test_malformed_documents_are_ignored_without_error(document: Any) -> None:
    detector = SessionEndDetector(end_timeout_s=1.0)
    detector.on_estimate(_valid(1.0), T0)
    detector.on_estimate(document, T0 + S // 5)
    assert detector.due(T0 + 10 * S) == _valid(1.0)


def test_a_later_valid_estimate_opens_a_new_session_stored_separately() -> None:
    detector = SessionEndDetector(end_timeout_s=1.0)
    first = _feed(detector, [_valid(1.0), _valid(1.1)], T0)
    assert detector.due(first + 2 * S) == _valid(1.1)
    # Invalid estimates after a stored session do not open a new one.
    later = _feed(detector, [_invalid()] * 3, first + 3 * S)
    assert detector.due(later + 2 * S) is None
    assert detector.due(later + 2 * S, end_requested=True) is None
    second_start = later + 60 * S
    documents = [_valid(2.0, second_start, second_start + 30 * S), _valid(2.1, second_start, second_start + 31 * S)]
    second = _feed(detector, documents, second_start + 31 * S)
    assert detector.due(second + S // 2) is None
    assert detector.due(second + S // 2, end_requested=True) is documents[1]
    assert detector.due(second + 2 * S) is None


def test_sessions_ended_by_request_and_by_silence_alternate() -> None:
    detector = SessionEndDetector(end_timeout_s=1.0)
    stored: list[dict[str, Any]] = []
    t = T0
    for k in range(6):
        start = t + 10 * S  # each session on data after the previous one's
        t = _feed(detector, [_valid(float(k), start, start + S), _invalid()], start)
        document = detector.due(t, end_requested=True) if k % 2 else detector.due(t + 2 * S)
        assert document is not None, k
        stored.append(document)
        assert detector.due(t + 2 * S) is None
    assert [d["segments"]["forearm"]["static_moment_kgm"]["value"] for d in stored] == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]


def test_a_backwards_clock_does_not_end_the_session() -> None:
    detector = SessionEndDetector(end_timeout_s=1.0)
    detector.on_estimate(_valid(1.0), T0)
    assert detector.due(T0 - 100 * S) is None
    assert detector.due(T0 + 2 * S) == _valid(1.0)


def test_the_stored_estimate_received_again_is_not_handed_out_again() -> None:
    detector = SessionEndDetector(end_timeout_s=1.0)
    final = _valid(1.0)
    detector.on_estimate(final, T0)
    assert detector.due(T0 + S // 10, end_requested=True) == final
    detector.on_estimate(copy.deepcopy(final), T0 + S // 5)  # still in flight when the end request came
    assert detector.due(T0 + 5 * S) is None
