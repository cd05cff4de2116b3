"""When a live session starts and ends: the subject, the services, the end message, input silence, a time limit.

Plain logic on the node's clock (ns); `session_recorder` adapts ROS to it and acts on what it returns.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import StrEnum

from bsp_ros.clinic.store.subject import check_pseudonymous_id
from bsp_ros.errors import InputError

__all__ = ["EndCause", "Reply", "SessionControl", "SessionEnd", "SessionStart", "StartCause", "naming_hint"]


class StartCause(StrEnum):
    """What started a session."""

    SERVICE = "service"  # bsp/session/start or bsp/session/start_retest
    INPUT = "input"  # auto_start: the wrench stream started
    RESET = "reset"  # bsp/session/reset: a fresh session in place of the discarded one


class EndCause(StrEnum):
    """What ended a session; every cause but RESET hands the session on to be identified and stored."""

    STOP = "stop"  # bsp/session/stop
    END_MESSAGE = "session_end"  # a message on bsp/session_end
    SILENCE = "silence"  # the wrench stream stopped for end_timeout_s
    TIME_LIMIT = "time_limit"  # max_session_s reached
    RESET = "reset"  # discarded: nothing is stored
    SHUTDOWN = "shutdown"  # the recorder stops: the session's bag is kept, not identified


@dataclass(frozen=True, kw_only=True)
class SessionStart:
    """A session that started: for whom, whether it is a same-day retest, when (node clock, ns) and why."""

    subject: str
    retest: bool
    started_ns: int
    cause: StartCause


@dataclass(frozen=True, kw_only=True)
class SessionEnd:
    """A session that ended: the session, when (node clock, ns) and why."""

    session: SessionStart
    ended_ns: int
    cause: EndCause

    @property
    def stored(self) -> bool:
        """Whether the session goes on to be identified and stored."""
        return self.cause not in (EndCause.RESET, EndCause.SHUTDOWN)


@dataclass(frozen=True, kw_only=True)
class Reply:
    """The answer to a service request: its ``success`` and ``message`` (std_srvs/Trigger), and what changed."""

    success: bool
    message: str
    started: SessionStart | None = None
    ended: SessionEnd | None = None


def naming_hint(node_name: str) -> str:
    """How to name the subject, for a log line or a refused request."""
    return (
        f"name the subject first: `ros2 param set /{node_name} subject <ID>` (a pseudonymous id such as P007), "
        "or launch with subject:=<ID>"
    )


@dataclass(kw_only=True)
class SessionControl:
    """The session state of `session_recorder`.

    A session is recording from a start (service, or with ``auto_start`` the wrench stream starting) until a
    stop (service or ``bsp/session/end`` message), ``end_timeout_s`` of silence on the wrench stream once it
    has flowed, or ``max_session_s``. A reset discards the running session and starts a new one at once.
    With ``auto_start`` a stream that goes on after an explicit stop starts no new session: the streams must
    fall silent first (or the start service be called).

    Attributes
    ----------
    node_name : the node's name, for the hints in refusals.
    end_timeout_s : silence on the wrench stream that ends a session, s.
    max_session_s : longest session, s.
    auto_start : start a session when the wrench stream starts.
    subject : the named subject (None: none yet; nothing is recorded).
    active : the running session, or None.
    """

    node_name: str
    end_timeout_s: float
    max_session_s: float
    auto_start: bool = False
    subject: str | None = None
    active: SessionStart | None = None
    last_input_ns: int | None = None
    session_input: bool = False  # the running session has received the wrench stream
    armed: bool = True  # auto_start may start a session at the next input (the streams were silent)
    _silent_warned: bool = field(default=False, repr=False)

    def name_subject(self, subject: str) -> str | None:
        """Name the subject of the next sessions; return the checked id (None for an empty one: unnamed).

        Raises
        ------
        InputError
            The id is not pseudonymous (a name, a birth date, spaces...), or a session is recording (stop it
            first: its data belong to the subject it started for).
        """
        checked = check_pseudonymous_id(subject) if subject else None
        if self.active is not None and checked != self.active.subject:
            raise InputError(
                f"a session of {self.active.subject} is recording: stop it (bsp/session/stop) before naming "
                "another subject"
            )
        self.subject = checked
        return checked

    def start(self, now_ns: int, retest: bool = False) -> Reply:
        """The start service: a session for the named subject, unless one is recording or none is named."""
        if self.subject is None:
            return Reply(success=False, message=f"no subject named: {naming_hint(self.node_name)}")
        if self.active is not None:
            return Reply(
                success=False,
                message=f"a session of {self.active.subject} is recording already: stop or reset it first",
            )
        started = self._begin(now_ns, retest, StartCause.SERVICE)
        kind = "retest" if retest else "session"
        return Reply(success=True, message=f"recording a {kind} of {self.subject}", started=started)

    def stop(self, now_ns: int, cause: EndCause = EndCause.STOP) -> Reply:
        """The stop service (or an end message): end the running session, to be identified and stored."""
        if self.active is None:
            return Reply(success=False, message="no session is recording")
        ended = self._end(now_ns, cause)
        return Reply(success=True, message=f"session of {ended.session.subject} ended: identifying it", ended=ended)

    def reset(self, now_ns: int) -> Reply:
        """The reset service: discard the running session (nothing stored) and start a new one for its subject."""
        if self.active is None:
            return Reply(success=False, message="no session is recording: nothing to reset")
        ended = self._end(now_ns, EndCause.RESET)
        started = self._begin(now_ns, ended.session.retest, StartCause.RESET)
        return Reply(
            success=True,
            message=f"session of {started.subject} discarded; recording a new one",
            started=started,
            ended=ended,
        )

    def on_input(self, now_ns: int) -> SessionStart | None:
        """A wrench message arrived; returns the session it starts (``auto_start``), if any."""
        self.last_input_ns = now_ns
        if self.active is not None:
            self.session_input = True
            return None
        if not (self.auto_start and self.armed and self.subject is not None):
            return None
        started = self._begin(now_ns, False, StartCause.INPUT)
        self.session_input = True
        return started

    def due(self, now_ns: int) -> SessionEnd | None:
        """The session that ends now by silence or its time limit, if any (call periodically)."""
        silent = self.last_input_ns is None or now_ns - self.last_input_ns > self.end_timeout_s * 1e9
        if silent:
            self.armed = True
        if self.active is None:
            return None
        if self.session_input and silent:
            return self._end(now_ns, EndCause.SILENCE)
        if now_ns - self.active.started_ns >= self.max_session_s * 1e9:
            return self._end(now_ns, EndCause.TIME_LIMIT)
        return None

    def unnamed_input(self) -> bool:
        """True once per stretch of input arriving with no subject named (to say so in the log once)."""
        if self.subject is not None or self.last_input_ns is None:
            self._silent_warned = False
            return False
        if self._silent_warned:
            return False
        self._silent_warned = True
        return True

    def _begin(self, now_ns: int, retest: bool, cause: StartCause) -> SessionStart:
        assert self.subject is not None
        self.active = SessionStart(subject=self.subject, retest=retest, started_ns=now_ns, cause=cause)
        self.session_input = False
        return self.active

    def _end(self, now_ns: int, cause: EndCause) -> SessionEnd:
        assert self.active is not None
        ended = SessionEnd(session=self.active, ended_ns=now_ns, cause=cause)
        self.active = None
        self.session_input = False
        # A stream still flowing after an explicit end starts no new session by itself.
        self.armed = cause is EndCause.SILENCE
        return ended
