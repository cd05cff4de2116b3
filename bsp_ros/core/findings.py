"""Typed findings: what the estimator found about a session, as a code with numbers, its text rendered from the code.

Every verdict and note of an identification is a :class:`Finding`. Its ``code`` (a :class:`FindingCode`) is
what callers decide on: the CLI's exit codes, the node's diagnostics level, the end of a live session, the
report's cause and advice. Its text, its severity and the plain cause and action a clinic reads are rendered
from :data:`SPECS`, keyed by the code, never parsed back. A few codes carry a note written by a lower layer
(the bag reader, the stream timing, the marker cleaning) verbatim in ``values["detail"]``.

Adding a code: a :class:`FindingCode` member, its :class:`FindingSpec` in ``findings_specs.py``, and a test
that makes the estimator produce it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

__all__ = [
    "Finding",
    "FindingCode",
    "FindingSpec",
    "Severity",
    "findings_of",
    "invalid_texts",
    "note",
    "note_texts",
    "plain_cause",
    "verdict_of",
]


class Severity(StrEnum):
    """How a finding bears on the estimate."""

    INVALID = "invalid"
    """The estimate cannot be used."""
    WEAK = "weak"
    """Valid, but qualified: a parameter is confounded or uncertain, or the model was chosen by the data."""
    NOTE = "note"
    """A note on the data or the model; the estimate stands as it is."""


class FindingCode(StrEnum):
    """Every kind of finding the estimator reports (closed vocabulary; the JSON's ``quality.findings[].code``)."""

    # Too little data or motion: the recording cannot give an estimate (bsp identify exits 3).
    TOO_FEW_SAMPLES = "too_few_samples"
    TOO_FEW_USABLE_SAMPLES = "too_few_usable_samples"
    NO_MOTION = "no_motion"
    ONE_DIRECTION = "one_direction"
    DIRECTION_UNCLEAR = "direction_unclear"
    NOT_YET_DETERMINED = "not_yet_determined"
    NOT_IDENTIFIABLE = "not_identifiable"
    # The model and the data disagree.
    FAR_OFF_SAMPLES = "far_off_samples"
    TOO_LITTLE_RELAXED = "too_little_relaxed"
    HANGS_ON_FEW_SAMPLES = "hangs_on_few_samples"
    MODEL_MISFIT = "model_misfit"
    STATIC_MOMENT_AT_BOUND = "static_moment_at_bound"
    UNMODELLED_EFFECT = "unmodelled_effect"
    ELASTIC_LACKING = "elastic_lacking"
    PERPENDICULAR_IMPLAUSIBLE = "perpendicular_implausible"
    STATIC_MOMENT_IMPLAUSIBLE = "static_moment_implausible"
    NOT_SAME_ARM = "not_same_arm"
    NON_FINITE = "non_finite"
    ROTATION_ASSUMED = "rotation_assumed"
    # The live wrench rotation: the cell's mounting stood in for a transform (note), or a transform disagrees (weak).
    ROTATION_FROM_MOUNTING = "rotation_from_mounting"
    ROTATION_DISAGREES = "rotation_disagrees"
    # Live inputs and checks.
    INPUT_WAITING = "input_waiting"
    INPUT_STALE = "input_stale"
    INTERNAL_ERROR = "internal_error"
    INPUT_UNUSABLE = "input_unusable"
    WAITING_FOR_CHECK = "waiting_for_check"
    WINDOW_WITHOUT_STD = "window_without_std"
    # Qualified estimates.
    CONFOUNDED = "confounded"
    UNCERTAIN_STATIC_MOMENT = "uncertain_static_moment"
    ELASTIC_TERM = "elastic_term"
    TREMOR_FRICTION = "tremor_friction"
    SPASTICITY = "spasticity"
    HAND_SLIPPED = "hand_slipped"
    DIRECTION_NOISY = "direction_noisy"
    # Notes on the model.
    FRICTION_SMOOTH = "friction_smooth"
    FRICTION_TRANSITION_WEAK = "friction_transition_weak"
    FIT_OUTLIERS_REMOVED = "fit_outliers_removed"
    ARM_ACTIVE = "arm_active"
    EMG_UNUSABLE = "emg_unusable"
    TREMOR = "tremor"
    WRENCH_SPIKES_REMOVED = "wrench_spikes_removed"
    MODEL_CHOICE_SPREAD = "model_choice_spread"
    DRIFT_MODELLED = "drift_modelled"
    POORLY_EXCITED = "poorly_excited"
    STATIC_MOMENT_OPEN = "static_moment_open"
    PARAMETER_AT_BOUND = "parameter_at_bound"
    FRICTION_SPEED_DEPENDENT = "friction_speed_dependent"
    PLACEMENT_WIDER = "placement_wider"
    GRIP_COMPLIANT = "grip_compliant"
    # A session at two speeds: the speed-dependent (neural) resistance measured apart from the passive part.
    SPEED_DEPENDENT_RESISTANCE = "speed_dependent_resistance"
    ELASTIC_FAMILY_CHOSEN = "elastic_family_chosen"
    HELD_FROM_CHECK = "held_from_check"
    FUSION_FAILED = "fusion_failed"
    PAPER_SPLIT_ARBITRARY = "paper_split_arbitrary"
    PAPER_STD_CLASSICAL = "paper_std_classical"
    # Notes written by the layers below the estimator, carried verbatim.
    DATA_NOTE = "data_note"
    BAG_NOTE = "bag_note"
    BAG_DAMAGED = "bag_damaged"
    BAG_POSSIBLY_DAMAGED = "bag_possibly_damaged"
    TIMING_NOTE = "timing_note"
    TARE_NOTE = "tare_note"
    PRIOR_NOTE = "prior_note"


@dataclass(frozen=True)
class FindingSpec:
    """What a code means: its severity, its text and, in a clinic's words, its cause and what to do.

    Attributes
    ----------
    severity : how the finding bears on the estimate.
    text : a ``str.format`` template over ``where`` and the finding's values, or a function of the finding.
    cause : the cause in plain words (empty for notes a clinic need not read).
    action : what to do about it (empty where nothing is to be done).
    """

    severity: Severity
    text: str | Callable[[Finding], str]
    cause: str = ""
    action: str = ""


@dataclass(frozen=True, kw_only=True)
class Finding:
    """One thing the estimator found.

    Attributes
    ----------
    code : what was found.
    where : the joint or segment it concerns (``"elbow"``, ``"forearm"``), or ``""`` for the session.
    values : the numbers (and names) its text is rendered from, in the units its key names.
    recording : the recording (1-based) of several identified together that it concerns, or None.
    """

    code: FindingCode
    where: str = ""
    values: Mapping[str, Any] = field(default_factory=dict)
    recording: int | None = None
    # The text a document carried, for a finding read back whose values JSON could not hold (an infinite ratio).
    written: str | None = field(default=None, compare=False, repr=False)

    @property
    def spec(self) -> FindingSpec:
        """The code's entry of :data:`SPECS`."""
        from bsp_ros.core.findings_specs import SPECS

        return SPECS[self.code]

    @property
    def severity(self) -> Severity:
        """How this finding bears on the estimate (fixed by its code)."""
        return self.spec.severity

    @property
    def text(self) -> str:
        """The finding in words, rendered from its code."""
        template = self.spec.text
        try:
            body = template.format(where=self.where, **self.values) if isinstance(template, str) else template(self)
        except (KeyError, TypeError, ValueError):
            if self.written is None:
                raise
            return self.written
        return body if self.recording is None else f"recording {self.recording}: {body}"

    def in_recording(self, recording: int) -> Finding:
        """This finding as one of recording ``recording`` (1-based) of several."""
        return Finding(code=self.code, where=self.where, values=self.values, recording=recording, written=self.written)

    def to_json(self) -> dict[str, Any]:
        """``{"code", "severity", "where", "text", "values"}`` (and ``recording`` where set): JSON-ready."""
        out: dict[str, Any] = {
            "code": str(self.code),
            "severity": str(self.severity),
            "where": self.where,
            "text": self.text,
            "values": {k: _json_value(v) for k, v in self.values.items()},
        }
        if self.recording is not None:
            out["recording"] = self.recording
        return out

    @classmethod
    def from_json(cls, block: Mapping[str, Any]) -> Finding:
        """The finding a :meth:`to_json` block holds.

        Raises
        ------
        ValueError
            The block's code is not a :class:`FindingCode`.
        """
        recording = block.get("recording")
        return cls(
            code=FindingCode(block["code"]),
            where=str(block.get("where", "")),
            values=dict(block.get("values") or {}),
            recording=int(recording) if recording is not None else None,
            written=str(block["text"]) if "text" in block else None,
        )


def note(code: FindingCode, detail: str) -> Finding:
    """A finding of a lower layer whose text is ``detail`` verbatim (the ``*_NOTE`` codes)."""
    return Finding(code=code, values={"detail": detail})


def findings_of(quality: Mapping[str, Any]) -> list[Finding]:
    """The findings of an estimate document's ``quality`` block (none for a document without them)."""
    out = []
    for block in quality.get("findings") or []:
        try:
            out.append(Finding.from_json(block))
        except (KeyError, TypeError, ValueError):
            continue  # a code from a newer version: its text stays in the message and warnings
    return out


def verdict_of(findings: Iterable[Finding]) -> Finding | None:
    """The first finding that makes an estimate invalid (the likeliest cause of the others), or None."""
    return next((f for f in findings if f.severity is Severity.INVALID), None)


def plain_cause(findings: Iterable[Finding]) -> tuple[str, str] | None:
    """The cause and the action, in a clinic's words, of the first finding that makes an estimate invalid (its
    joint or segment named); None where none does or it has no plain cause."""
    verdict = verdict_of(findings)
    if verdict is None or not verdict.spec.cause:
        return None
    where = verdict.where.replace("_", " ")
    return verdict.spec.cause.format(where=where), verdict.spec.action or "repeat the session"


def invalid_texts(findings: Iterable[Finding]) -> list[str]:
    """The texts of the findings that make an estimate invalid, in order."""
    return [f.text for f in findings if f.severity is Severity.INVALID]


def note_texts(findings: Iterable[Finding]) -> list[str]:
    """The texts of the findings that qualify or annotate an estimate (weak and note), in order."""
    return [f.text for f in findings if f.severity is not Severity.INVALID]


def _json_value(value: Any) -> Any:
    """A finding's value as JSON: numbers as float or int (null where not finite: strict JSON), sequences as lists."""
    if isinstance(value, bool | str | int) or value is None:
        return value
    if isinstance(value, list | tuple):
        return [_json_value(v) for v in value]
    number = float(value)
    return number if math.isfinite(number) else None
