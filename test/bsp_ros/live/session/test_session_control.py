"""When live sessions start and end (SessionControl): the subject, the services, the wrench stream, the limits."""

from __future__ import annotations

import pytest

from bsp_ros.errors import InputError
from bsp_ros.live.session.control import EndCause, SessionControl, StartCause

S = 1_000_000_000  # ns per s
T0 = 1_700_000_000 * S


def _control(auto_start: bool = False, max_session_s: float = 1800.0) -> SessionControl:
    return SessionControl(
        node_name="session_recorder", end_timeout_s=5.0, max_session_s=max_session_s, auto_start=auto_start
    )


def _stream(control: SessionControl, start_ns: int, seconds: float, period_ns: int = S // 10) -> int:
    """The wrench streaming at 10 Hz for ``seconds`` (the control ticked as the node's timer would); its last time."""
    t = start_ns
    while t < start_ns + seconds * S:
        control.on_input(t)
        assert control.due(t) is None
        t += period_ns
    return t - period_ns


def test_without_a_subject_nothing_starts_and_the_refusal_says_how_to_name_one() -> None:
    control = _control(auto_start=True)
    reply = control.start(T0)
    assert not reply.success and reply.started is None
    assert "ros2 param set /session_recorder subject" in reply.message and "subject:=" in reply.message
    _stream(control, T0, 2.0)
    assert control.active is None
    assert control.unnamed_input() and not control.unnamed_input()  # said once per stretch


@pytest.mark.parametrize("subject", ["Maria_Garcia", "garcia_19840312", "P 007", "a@b.c"])
def test_an_identifying_or_malformed_subject_is_refused(subject: str) -> None:
    with pytest.raises(InputError):
        _control().name_subject(subject)


def test_the_subject_cannot_change_while_a_session_records() -> None:
    control = _control()
    control.name_subject("P007")
    assert control.start(T0).success
    with pytest.raises(InputError, match="P007 is recording"):
        control.name_subject("P008")
    assert control.name_subject("P007") == "P007"
    ended = control.stop(T0 + 10 * S).ended
    assert ended is not None and ended.cause is EndCause.STOP and ended.stored
    assert control.name_subject("P008") == "P008"


def test_a_started_session_waits_for_the_stream_then_ends_with_its_silence() -> None:
    control = _control()
    control.name_subject("P007")
    reply = control.start(T0, retest=True)
    assert reply.success and reply.started is not None and reply.started.retest
    assert not control.start(T0 + S).success  # one at a time
    assert control.due(T0 + 60 * S) is None  # no input yet: the robot has not started
    last = _stream(control, T0 + 60 * S, 30.0)
    assert control.due(last + 4 * S) is None
    ended = control.due(last + 6 * S)
    assert ended is not None and ended.cause is EndCause.SILENCE and ended.session.retest
    assert control.active is None


def test_auto_start_follows_the_stream_but_not_after_an_explicit_stop_until_it_falls_silent() -> None:
    control = _control(auto_start=True)
    control.name_subject("P007")
    control.on_input(T0)
    assert control.active is not None and control.active.cause is StartCause.INPUT
    last = _stream(control, T0, 10.0)
    assert control.stop(last, EndCause.END_MESSAGE).success
    last = _stream(control, last + S // 10, 10.0)  # the stream goes on: no new session
    assert control.active is None
    assert control.due(last + 6 * S) is None and control.active is None  # silence re-arms
    control.on_input(last + 20 * S)
    assert control.active is not None and control.active.started_ns == last + 20 * S


def test_a_session_ends_at_its_time_limit_and_a_reset_starts_it_afresh() -> None:
    control = _control(max_session_s=60.0)
    control.name_subject("P007")
    assert not control.reset(T0).success  # nothing to reset
    control.start(T0)
    reply = control.reset(T0 + 5 * S)
    assert reply.ended is not None and reply.ended.cause is EndCause.RESET and not reply.ended.stored
    assert reply.started is not None and reply.started.cause is StartCause.RESET
    last = _stream(control, T0 + 5 * S, 59.0)  # 59 s after the reset: the limit counts from it
    ended = control.due(last + 2 * S)
    assert ended is not None and ended.cause is EndCause.TIME_LIMIT
    assert ended.ended_ns - ended.session.started_ns >= 60 * S
