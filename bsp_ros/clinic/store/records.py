"""The stored session as plain data: quantities, quality and one session record."""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field
from typing import Any

from bsp_ros.core.estimate_schema import Quantity
from bsp_ros.core.findings import Finding, verdict_of

SOURCES = ("data", "prior", "data+prior")
GROUPS = ("segments", "joints")
ARMS = ("left", "right")
AFFECTED = ("left", "right", "both", "neither")

_EPOCH = dt.datetime(1970, 1, 1, tzinfo=dt.timezone.utc)

__all__ = [
    "AFFECTED",
    "ARMS",
    "GROUPS",
    "SOURCES",
    "ParamKey",
    "Quality",
    "Quantity",
    "SessionRecord",
    "SubjectRecord",
    "SubjectSummary",
    "describe_body",
    "format_time",
    "ns_to_datetime",
]

# A stored quantity is the estimate's own: value, std, source and, where the estimate has one, its budget.
ParamKey = tuple[str, str, str]
"""``(group, part, quantity)``, e.g. ``("joints", "elbow", "coulomb_nm")``."""


@dataclass(frozen=True, kw_only=True)
class Quality:
    """How far an estimate can be trusted.

    Attributes
    ----------
    valid : the estimator's overall validity flag.
    n_samples : samples used, if reported.
    condition_number : condition number of the regression, None if not finite or not reported.
    residual_rms_nm : RMS residual moment per joint (N m).
    warnings : the estimator's warnings, in order.
    tare_applied : whether a tare (sensor offset and handle payload) was subtracted; False when not recorded.
    tare_file : the tare file's name, if one was applied.
    message : the estimator's one-line verdict (why it is not valid, if it is not).
    findings : the estimator's typed findings (none for sessions stored before it gave them).
    """

    valid: bool
    n_samples: int | None = None
    condition_number: float | None = None
    residual_rms_nm: dict[str, float] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()
    tare_applied: bool = False
    tare_file: str | None = None
    message: str = ""
    findings: tuple[Finding, ...] = ()

    def verdict(self) -> Finding | None:
        """The first finding that made the estimate invalid, or None."""
        return verdict_of(self.findings)


@dataclass(frozen=True, kw_only=True)
class SessionRecord:
    """One identification session of one subject.

    Attributes
    ----------
    subject : pseudonymous subject id.
    session_time_ns : session start, ns since the Unix epoch (UTC).
    source : the recording the estimate came from (a bag or file name, no directories).
    method : the identification method, if recorded.
    config : the method's configuration.
    subject_info : anthropometric inputs for priors (``body_mass_kg``, ``height_m``, ``sex``), if given.
    estimate_schema : the estimate's schema tag.
    quality : validity and fit diagnostics.
    parameters : every quantity, keyed by ``(group, part, quantity)``.
    id : row id once stored, else None.
    added_ns : when the session was stored, ns since the epoch; None before.
    repeatability : the estimate's ``repeatability`` block (within-session spread: method, per-parameter
        SEM, see :mod:`bsp_ros.clinic.cycles`), keyed by ``group.part.quantity``; empty if none was computed.
        It describes one session; it never judges a change between days (see :mod:`bsp_ros.clinic.mdc`).
    arm : the measured arm, ``left`` or ``right``; None if not recorded.
    retest : whether this session is a retest: the same subject and arm measured again on the same day after
        re-attaching the arm (its pair feeds the day-to-day measurement error, not the trend).
    cell : the robot cell (installation) the session was recorded in; ``""`` if not named.
    content_sha256 : hash of the recording's content (or of the estimate's), so one recording is stored once.
    passive_curves : joint -> ``{"angle_deg": [...], "moment_nm": [...], "std_nm": [...]}``, if estimated.
    number : the session's number within its subject (1 = first in time), set when read from the store.
    passive_model : the passive model the identification used (``diagnostics.passive_model``: ``auto``'s choice,
        the elastic fallback's), None if the estimate did not say or the session was stored before it was kept.
    """

    subject: str
    session_time_ns: int
    source: str
    method: str | None
    config: dict[str, Any]
    subject_info: dict[str, Any]
    estimate_schema: str
    quality: Quality
    parameters: dict[ParamKey, Quantity]
    id: int | None = None
    added_ns: int | None = None
    repeatability: dict[str, Any] = field(default_factory=dict)
    arm: str | None = None
    retest: bool = False
    cell: str = ""
    content_sha256: str | None = None
    passive_curves: dict[str, Any] = field(default_factory=dict)
    number: int | None = None
    passive_model: str | None = None

    @property
    def session_time(self) -> dt.datetime:
        """The session start as an aware UTC datetime."""
        return ns_to_datetime(self.session_time_ns)


@dataclass(frozen=True)
class SubjectRecord:
    """What is known of a subject once, applied to every session: body data for priors and the arms.

    Attributes
    ----------
    subject : pseudonymous subject id.
    body_mass_kg, height_m, sex : anthropometric inputs of the priors (None: not given).
    arm : the arm measured by default, ``left`` or ``right`` (None: not given).
    affected : which arm is affected (``left``, ``right``, ``both``, ``neither``; None: not given).
    """

    subject: str
    body_mass_kg: float | None = None
    height_m: float | None = None
    sex: str | None = None
    arm: str | None = None
    affected: str | None = None

    def body(self) -> dict[str, Any]:
        """The body data that are set, keyed as a session's ``subject_info``."""
        found = {"body_mass_kg": self.body_mass_kg, "height_m": self.height_m, "sex": self.sex}
        return {k: v for k, v in found.items() if v is not None}

    def differs_from(self, subject_info: dict[str, Any]) -> bool:
        """Whether a session's body data (what its prior was made with) contradict or lack what this record sets."""
        return any(subject_info.get(key) != value for key, value in self.body().items())

    def identify_options(self) -> str:
        """The `bsp identify` options that make an estimate's prior from this record's body data."""
        flags = {"body_mass_kg": "--body-mass", "height_m": "--height", "sex": "--sex"}
        return " ".join(
            f"{flags[key]} {value:g}" if isinstance(value, float) else f"{flags[key]} {value}"
            for key, value in self.body().items()
        )

    def arm_status(self, arm: str | None) -> str | None:
        """``affected`` / ``unaffected`` for ``arm``, None if unknown."""
        if arm is None or self.affected is None:
            return None
        return "affected" if self.affected in (arm, "both") else "unaffected"


@dataclass(frozen=True)
class SubjectSummary:
    """A subject's sessions at a glance.

    Attributes
    ----------
    subject : pseudonymous subject id.
    n_sessions : number of stored sessions.
    first_ns, last_ns : the first and last session start, ns since the epoch.
    n_invalid : sessions whose estimate is flagged not valid.
    """

    subject: str
    n_sessions: int
    first_ns: int
    last_ns: int
    n_invalid: int


def ns_to_datetime(time_ns: int) -> dt.datetime:
    """``time_ns`` (ns since the Unix epoch) as an aware UTC datetime (microsecond resolution)."""
    return _EPOCH + dt.timedelta(microseconds=time_ns // 1000)


def format_time(time_ns: int) -> str:
    """``time_ns`` as ISO 8601 UTC to the second, e.g. ``2024-03-01T09:30:00Z``."""
    return ns_to_datetime(time_ns).strftime("%Y-%m-%dT%H:%M:%SZ")


def describe_body(subject_info: dict[str, Any]) -> str:
    """A session's body data in words, e.g. ``female, 68 kg, 1.65 m``."""
    if not subject_info:
        return "no body data"
    mass, height = subject_info.get("body_mass_kg"), subject_info.get("height_m")
    return ", ".join(
        (
            str(subject_info.get("sex", "sex not given")),
            "body mass not given (population prior)" if mass is None else f"{float(mass):g} kg",
            "no height" if height is None else f"{float(height):g} m",
        )
    )
