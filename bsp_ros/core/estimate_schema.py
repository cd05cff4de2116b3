"""The estimate as typed, frozen objects, and its JSON (schema ``bsp_ros/core/estimate/1``, docs/contract.md).

An :class:`Estimate` is what every consumer reads: the CLI, the node's messages, the weight support, the session
store and the report. JSON is only its edge: :meth:`Estimate.to_json` writes the document docs/contract.md
describes, and :meth:`Estimate.from_json` reads one back, keeping every key it does not type (a newer version's)
in ``extra`` so that nothing recorded is lost and the round trip is exact.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field, replace
from enum import StrEnum
from typing import Any

from bsp_ros.core.estimate_blocks import BagSection, PlacementBlock, RotationBlock, TareBlock, TimingBlock, typed_block
from bsp_ros.core.findings import Finding, Severity, findings_of, verdict_of
from bsp_ros.core.methods import LiveMode, Method
from bsp_ros.core.quantities import PASSIVE_CURVE

__all__ = ["SCHEMA", "Estimate", "Level", "Quality", "Quantity", "Source"]

SCHEMA = "bsp_ros/core/estimate/1"

#: The typed blocks of the ``quality`` block and of the document (beside their core keys), by key.
QUALITY_BLOCKS = ("tare", "timing", "rotation", "marker_placement")
ESTIMATE_BLOCKS = ("bag", "bags")


class Source(StrEnum):
    """Where a quantity's value comes from."""

    DATA = "data"
    PRIOR = "prior"
    DATA_PRIOR = "data+prior"


class Level(StrEnum):
    """The verdict in one word."""

    OK = "ok"
    WEAK = "weak"
    INVALID = "invalid"


@dataclass(frozen=True, kw_only=True)
class Quantity:
    """One estimated quantity.

    Attributes
    ----------
    value, std : the estimate and one standard deviation, in the unit its key names; None where not computed.
    source : data, prior or both.
    budget : each named source of uncertainty's standard uncertainty (their squares sum to ``std`` squared), for
        the quantities the identification decided; None elsewhere.
    """

    value: float | None
    std: float | None
    source: Source
    budget: Mapping[str, float | None] | None = None

    @property
    def finite(self) -> bool:
        """Whether value and std are both numbers."""
        return self.value is not None and self.std is not None and math.isfinite(self.value + self.std)

    def largest_term(self) -> tuple[str, float] | None:
        """The budget's largest term and its share of the variance (0-1), or None without a budget."""
        if not self.budget or not self.std:
            return None
        term, u = max(((t, u or 0.0) for t, u in self.budget.items()), key=lambda pair: pair[1])
        return term, u**2 / self.std**2

    def to_json(self) -> dict[str, Any]:
        """``{"value", "std", "source"}``, and ``budget`` where there is one."""
        out: dict[str, Any] = {"value": self.value, "std": self.std, "source": str(self.source)}
        if self.budget is not None:
            out["budget"] = dict(self.budget)
        return out

    @classmethod
    def from_json(cls, block: Mapping[str, Any]) -> Quantity:
        """The quantity of a ``{"value", "std", "source"}`` block."""
        budget = block.get("budget")
        return cls(
            value=_number(block.get("value")),
            std=_number(block.get("std")),
            source=Source(block.get("source", "data")),
            budget=dict(budget) if isinstance(budget, Mapping) else None,
        )


@dataclass(frozen=True, kw_only=True)
class Quality:
    """How far the estimate can be trusted.

    Attributes
    ----------
    valid : whether the data support the estimate.
    level : ok, weak or invalid.
    message : the verdict in one line (the invalid findings' texts, or a summary).
    findings : what the estimator found, typed.
    warnings : the texts of the weak and note findings.
    n_samples : samples used.
    condition_number : of the column-scaled regressor, None where not finite.
    residual_rms_nm : per joint, the torque residual's RMS.
    tare : whether a tare was subtracted, and the sensor zero's share of the std (``tare``).
    timing : the wrench delay compensated (``timing``).
    rotation : where the wrench frame's rotation came from (``rotation``).
    marker_placement : the markers' placement the std holds (``marker_placement``).
    extra : the other keys of the JSON's ``quality`` block (removed samples, contact point, assumptions...).
    key_order : the keys of the typed blocks and of ``extra`` in the document's order (as read, or as set); those
        not named in it follow, ``extra``'s first.

    Each typed block is None where the document lacks it (or holds it in a shape its type does not write: it then
    stays in ``extra`` as it is).
    """

    valid: bool
    level: Level
    message: str
    findings: tuple[Finding, ...] = ()
    warnings: tuple[str, ...] = ()
    n_samples: int = 0
    condition_number: float | None = None
    residual_rms_nm: Mapping[str, float] = field(default_factory=dict)
    tare: TareBlock | None = None
    timing: TimingBlock | None = None
    rotation: RotationBlock | None = None
    marker_placement: PlacementBlock | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)
    key_order: tuple[str, ...] = ()

    @property
    def verdict(self) -> Finding | None:
        """The first finding that makes the estimate invalid, or None."""
        return verdict_of(self.findings)

    @property
    def tare_applied(self) -> bool:
        """Whether a tare was subtracted."""
        return self.tare is not None and self.tare.applied

    @property
    def tare_file(self) -> str | None:
        """The applied tare's file name, or None."""
        return self.tare.file if self.tare is not None else None

    def with_finding(self, finding: Finding, at: int | None = None) -> Quality:
        """This quality with ``finding`` added: an invalid one first, its text leading the ``message``, the
        estimate made invalid; any other last, its text into the ``warnings`` (at index ``at``, else last)."""
        if finding.severity is Severity.INVALID:
            # The likeliest cause of what else the estimate found (a lost transform makes the model misfit): first.
            message = finding.text + (f"; {self.message}" if not self.valid else "")
            return replace(self, findings=(finding, *self.findings), message=message, valid=False, level=Level.INVALID)
        warnings = list(self.warnings)
        warnings.insert(len(warnings) if at is None else at, finding.text)
        return replace(self, findings=(*self.findings, finding), warnings=tuple(warnings))

    def with_extra(self, keys: Mapping[str, Any]) -> Quality:
        """This quality with the untyped blocks ``keys`` (offset sensitivity...) set, after those it has.

        Raises
        ------
        ValueError
            A key is one of the typed blocks' (set those with their own ``with_...``).
        """
        _check_untyped(keys, QUALITY_BLOCKS)
        return replace(self, extra={**self.extra, **keys}, key_order=_placed(self._blocks(), keys))

    def with_tare(self, tare: TareBlock) -> Quality:
        """This quality with its ``tare`` block (in its place, or after the blocks it has)."""
        return replace(self, tare=tare, key_order=_placed(self._blocks(), ("tare",)))

    def with_timing(self, timing: TimingBlock) -> Quality:
        """This quality with its ``timing`` block (in its place, or after the blocks it has)."""
        return replace(self, timing=timing, key_order=_placed(self._blocks(), ("timing",)))

    def with_rotation(self, rotation: RotationBlock) -> Quality:
        """This quality with its ``rotation`` block (in its place, or after the blocks it has)."""
        return replace(self, rotation=rotation, key_order=_placed(self._blocks(), ("rotation",)))

    def _blocks(self) -> dict[str, object]:
        """The JSON of the typed blocks present and of ``extra``, in the document's order (see ``key_order``)."""
        typed = {
            key: block.to_json()
            for key, block in (
                ("tare", self.tare),
                ("timing", self.timing),
                ("rotation", self.rotation),
                ("marker_placement", self.marker_placement),
            )
            if block is not None
        }
        return _in_order({**self.extra, **typed}, self.key_order)

    def to_json(self) -> dict[str, Any]:
        """The JSON ``quality`` block, its keys in docs/contract.md's order and then the others."""
        return {
            "valid": self.valid,
            "n_samples": self.n_samples,
            "condition_number": self.condition_number,
            "residual_rms_nm": dict(self.residual_rms_nm),
            "warnings": list(self.warnings),
            "message": self.message,
            "findings": [f.to_json() for f in self.findings],
            "level": str(self.level),
            **self._blocks(),
        }

    @classmethod
    def from_json(cls, block: Mapping[str, Any]) -> Quality:
        """The quality of a JSON ``quality`` block (a block without findings, from before they existed, has none)."""
        typed = {"valid", "n_samples", "condition_number", "residual_rms_nm", "warnings", "message", "findings"}
        valid = bool(block.get("valid"))
        level = block.get("level") or ("ok" if valid else "invalid")
        blocks = {k: v for k, v in block.items() if k not in typed and k != "level"}
        tare = typed_block(TareBlock.from_json, blocks.get("tare"))
        timing = typed_block(TimingBlock.from_json, blocks.get("timing"))
        rotation = typed_block(RotationBlock.from_json, blocks.get("rotation"))
        placement = typed_block(PlacementBlock.from_json, blocks.get("marker_placement"))
        typed_blocks = {"tare": tare, "timing": timing, "rotation": rotation, "marker_placement": placement}
        return cls(
            valid=valid,
            level=Level(level),
            message=str(block.get("message", "")),
            findings=tuple(findings_of(block)),
            warnings=tuple(str(w) for w in block.get("warnings") or ()),
            n_samples=int(block.get("n_samples") or 0),
            condition_number=_number(block.get("condition_number")),
            residual_rms_nm={
                str(k): number
                for k, v in (block.get("residual_rms_nm") or {}).items()
                if (number := _number(v)) is not None
            },
            tare=tare,
            timing=timing,
            rotation=rotation,
            marker_placement=placement,
            extra={k: v for k, v in blocks.items() if typed_blocks.get(k) is None},
            key_order=tuple(blocks),
        )


@dataclass(frozen=True, kw_only=True)
class Estimate:
    """An identified arm: its segments and joints, how far to trust them, and where they came from.

    Attributes
    ----------
    method : the identification method.
    segments : segment -> quantity key -> quantity (``static_moment_kgm``, ``mass_kg``, ...).
    joints : joint -> quantity key -> quantity (``coulomb_nm``, ...).
    passive_curves : joint -> its passive moment curve (docs/contract.md), where estimated.
    quality : the verdict and what the std holds.
    subject : the body data the prior used.
    diagnostics : the figures behind the verdict (parameters, correlation, ...).
    software : name and version of what made it.
    session : times, source, configuration; None for a live estimate before its first window.
    bag : what the read of its bag found (``bag``); None for a live estimate or several recordings.
    bags : with several recordings identified together, each bag's section (``bags``); else None.
    extra : the document's other top-level keys (``mode``, ``repeatability``, ``speed_dependence``...).
    key_order : the keys of ``bag``, ``bags`` and ``extra`` in the document's order (as read, or as set); those not
        named in it follow, ``extra``'s first.
    schema : the schema tag.
    """

    method: Method
    segments: Mapping[str, Mapping[str, Quantity]]
    joints: Mapping[str, Mapping[str, Quantity]]
    quality: Quality
    passive_curves: Mapping[str, Any] = field(default_factory=dict)
    subject: Mapping[str, Any] | None = None
    diagnostics: Mapping[str, Any] | None = None
    software: Mapping[str, Any] | None = None
    session: Mapping[str, Any] | None = None
    bag: BagSection | None = None
    bags: tuple[BagSection, ...] | None = None
    extra: Mapping[str, Any] = field(default_factory=dict)
    key_order: tuple[str, ...] = ()
    schema: str = SCHEMA

    @property
    def valid(self) -> bool:
        """Whether the data support the estimate."""
        return self.quality.valid

    def quantity(self, key: str, owner: str) -> Quantity | None:
        """The quantity ``key`` of segment or joint ``owner``, or None."""
        group = self.segments if owner in self.segments else self.joints
        return group.get(owner, {}).get(key)

    def quantities(self) -> Iterator[tuple[str, str, str, Quantity]]:
        """``(group, owner, key, quantity)`` for every quantity, segments first (``segments``/``joints``)."""
        for group, owners in (("segments", self.segments), ("joints", self.joints)):
            for owner, quantities in owners.items():
                for key, q in quantities.items():
                    yield group, owner, key, q

    @property
    def mode(self) -> LiveMode | None:
        """The live mode that made it (the ``mode`` block), or None for an offline estimate."""
        mode = self.extra.get("mode")
        return LiveMode(mode) if mode is not None else None

    @classmethod
    def invalid(cls, method: Method, finding: Finding) -> Estimate:
        """An estimate with no parameters, made invalid by ``finding`` (live inputs not usable)."""
        quality = Quality(valid=False, level=Level.INVALID, message=finding.text, findings=(finding,))
        return cls(method=method, segments={}, joints={}, quality=quality)

    def with_quality(self, quality: Quality) -> Estimate:
        """This estimate with ``quality`` in place of its own."""
        return replace(self, quality=quality)

    def with_findings(self, *findings: Finding, at: int | None = None) -> Estimate:
        """This estimate with ``findings`` added in order (:meth:`Quality.with_finding`; ``at``: where the first
        weak or note finding's text goes in the warnings, the next ones after it)."""
        quality = self.quality
        for finding in findings:
            quality = quality.with_finding(finding, at)
            if at is not None and finding.severity is not Severity.INVALID:
                at += 1
        return replace(self, quality=quality)

    def with_extra(self, keys: Mapping[str, Any]) -> Estimate:
        """This estimate with the untyped top-level blocks ``keys`` (``mode``, ``precision``...) set, after its own.

        Raises
        ------
        ValueError
            A key is ``bag`` or ``bags`` (set those with :meth:`with_bag`).
        """
        _check_untyped(keys, ESTIMATE_BLOCKS)
        return replace(self, extra={**self.extra, **keys}, key_order=_placed(self._blocks(), keys))

    def with_bag(self, section: BagSection, *, recording: int | None = None) -> Estimate:
        """This estimate with the ``bag`` section of its one bag, or (``recording`` k of several) with ``section``
        appended to ``bags``."""
        if recording is None:
            return replace(self, bag=section, key_order=_placed(self._blocks(), ("bag",)))
        bags = (*(self.bags or ()), section)
        return replace(self, bags=bags, key_order=_placed(self._blocks(), ("bags",)))

    def _blocks(self) -> dict[str, object]:
        """The JSON of ``bag``, ``bags`` and ``extra``, in the document's order (see ``key_order``)."""
        typed: dict[str, object] = {}
        if self.bag is not None:
            typed["bag"] = self.bag.to_json()
        if self.bags is not None:
            typed["bags"] = [b.to_json() for b in self.bags]
        return _in_order({**self.extra, **typed}, self.key_order)

    def with_mode(self, mode: LiveMode) -> Estimate:
        """This estimate as the live ``mode`` made it (the top-level ``mode``, after its other blocks)."""
        return self.with_extra({"mode": mode.value})

    def to_json(self) -> dict[str, Any]:
        """The docs/contract.md document (JSON-ready: no NaN; key order as written by the estimator)."""
        joints: dict[str, dict[str, Any]] = {}
        for joint, quantities in self.joints.items():
            joints[joint] = {key: q.to_json() for key, q in quantities.items()}
            if joint in self.passive_curves:
                joints[joint][PASSIVE_CURVE] = self.passive_curves[joint]
        out: dict[str, Any] = {
            "schema": self.schema,
            "method": str(self.method),
            "segments": {s: {k: q.to_json() for k, q in qs.items()} for s, qs in self.segments.items()},
            "joints": joints,
            "quality": self.quality.to_json(),
        }
        for key in ("subject", "diagnostics", "software", "session"):
            value = getattr(self, key)
            if value is not None:
                out[key] = value
        return {**out, **self._blocks()}

    @classmethod
    def from_json(cls, document: Mapping[str, Any]) -> Estimate:
        """The estimate of a docs/contract.md document; keys it does not type stay in ``extra``.

        Raises
        ------
        KeyError, TypeError, ValueError
            The document lacks ``quality``, holds a quantity that is not ``{"value", "std", "source"}`` or a
            ``method`` that is none of :class:`Method` (a document without one is the ``joint`` method's).
        """
        joints: dict[str, dict[str, Quantity]] = {}
        curves: dict[str, Any] = {}
        for joint, block in (document.get("joints") or {}).items():
            joints[joint] = {k: Quantity.from_json(q) for k, q in block.items() if k != PASSIVE_CURVE}
            if PASSIVE_CURVE in block:
                curves[joint] = block[PASSIVE_CURVE]
        typed = {"schema", "method", "segments", "joints", "quality", "subject", "diagnostics", "software", "session"}
        blocks = {k: v for k, v in document.items() if k not in typed}
        bag = typed_block(BagSection.from_json, blocks.get("bag"))
        bags = _typed_bags(blocks.get("bags"))
        return cls(
            schema=str(document.get("schema", SCHEMA)),
            method=Method(str(document.get("method", Method.JOINT))),
            segments={
                s: {k: Quantity.from_json(q) for k, q in block.items()}
                for s, block in (document.get("segments") or {}).items()
            },
            joints=joints,
            passive_curves=curves,
            quality=Quality.from_json(document["quality"]),
            subject=document.get("subject"),
            diagnostics=document.get("diagnostics"),
            software=document.get("software"),
            session=document.get("session"),
            bag=bag,
            bags=bags,
            extra={k: v for k, v in blocks.items() if {"bag": bag, "bags": bags}.get(k) is None},
            key_order=tuple(blocks),
        )


def _typed_bags(sections: object) -> tuple[BagSection, ...] | None:
    """The ``bags`` list typed, where every section is a :class:`BagSection`'s exactly; else None."""
    if not isinstance(sections, list):
        return None
    typed = [typed_block(BagSection.from_json, section) for section in sections]
    return tuple(t for t in typed if t is not None) if all(t is not None for t in typed) else None


def _check_untyped(keys: Iterable[str], typed: tuple[str, ...]) -> None:
    """Refuse a typed block's key among untyped ones (its typed field would hide it)."""
    if clash := [key for key in keys if key in typed]:
        raise ValueError(f"{clash} are typed blocks: set them with their own with_... operation")


def _in_order(blocks: Mapping[str, object], key_order: tuple[str, ...]) -> dict[str, object]:
    """``blocks`` with the keys ``key_order`` names first, in its order, then the others in theirs."""
    named = {key: blocks[key] for key in key_order if key in blocks}
    return {**named, **{k: v for k, v in blocks.items() if k not in named}}


def _placed(blocks: Mapping[str, object], keys: Iterable[str]) -> tuple[str, ...]:
    """The key order of ``blocks`` with ``keys`` set: each in its place, a new one after the others."""
    return tuple(dict.fromkeys([*blocks, *keys]))


def _number(value: Any) -> float | None:
    """A JSON number as float; null (or anything not a number) as None."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value)
