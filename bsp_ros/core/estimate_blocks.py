"""The estimate's typed blocks beside its quantities: ``quality.tare``, ``quality.timing``, ``quality.rotation``,
``quality.marker_placement`` and the ``bag`` section (docs/contract.md, section 4).

Each is a frozen dataclass whose ``to_json`` writes the block as the estimator writes it, key order included, and
whose ``from_json`` reads one back. :func:`typed_block` types a block only where that round trip gives the block
back exactly; a block of another shape (a newer version's, one written by hand) is left to the caller's ``extra``
as it is, so that nothing recorded is lost.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from enum import StrEnum
from typing import Protocol, TypeVar

__all__ = [
    "BagSection",
    "DelayBlock",
    "DelaySource",
    "PlacementBlock",
    "RotationBlock",
    "SensorZero",
    "TareBlock",
    "TimingBlock",
    "typed_block",
]


class _Block(Protocol):
    def to_json(self) -> dict[str, object]: ...


BlockT = TypeVar("BlockT", bound=_Block)


def typed_block(read: Callable[[Mapping[str, object]], BlockT], block: object) -> BlockT | None:
    """``read(block)`` where that types ``block`` exactly (its ``to_json()`` is ``block``, key order included), else
    None: the block then stays untyped where it was found.

    Parameters
    ----------
    read : a block type's ``from_json``.
    block : the JSON value found under the block's key.
    """
    if not isinstance(block, Mapping):
        return None
    try:
        typed = read(block)
        same = json.dumps(typed.to_json()) == json.dumps(block)
    except (KeyError, TypeError, ValueError):
        return None
    return typed if same else None


@dataclass(frozen=True, kw_only=True)
class SensorZero:
    """The untared sensor's zero assumed within ``force_n`` (N) and ``moment_nm`` (N m), 1 SD per sensor axis."""

    force_n: float
    moment_nm: float

    def to_json(self) -> dict[str, object]:
        """``{"force_n", "moment_nm"}``."""
        return {"force_n": self.force_n, "moment_nm": self.moment_nm}

    @classmethod
    def from_json(cls, block: Mapping[str, object]) -> SensorZero:
        """The zero of a ``{"force_n", "moment_nm"}`` block."""
        return cls(force_n=_float(block["force_n"]), moment_nm=_float(block["moment_nm"]))


@dataclass(frozen=True, kw_only=True)
class TareBlock:
    """``quality.tare``: whether a tare was subtracted, and the sensor zero's share of the std.

    Attributes
    ----------
    applied : a tare (sensor offset and handle payload) was subtracted.
    file : the tare's file name (or source), None without a tare.
    zero_sd : without a tare, the zero the std assumes; None with one (or where no std was added).
    std_added : per parameter (``<quantity>/<owner>``) the standard uncertainty the zero added, in the parameter's
        unit; None where the estimate could not be differentiated.
    """

    applied: bool
    file: str | None
    zero_sd: SensorZero | None = None
    std_added: Mapping[str, float] | None = None

    def to_json(self) -> dict[str, object]:
        """``{"applied", "file"}``, then ``zero_sd`` and ``std_added`` where known."""
        out: dict[str, object] = {"applied": self.applied, "file": self.file}
        if self.zero_sd is not None:
            out["zero_sd"] = self.zero_sd.to_json()
        if self.std_added is not None:
            out["std_added"] = dict(self.std_added)
        return out

    @classmethod
    def from_json(cls, block: Mapping[str, object]) -> TareBlock:
        """The tare block of a document (``applied`` a bool, ``file`` a name or null)."""
        applied, file = block["applied"], block.get("file")
        if not isinstance(applied, bool) or not (file is None or isinstance(file, str)):
            raise TypeError(f"quality.tare: applied must be a bool and file a name or null, got {dict(block)!r:.80}")
        zero = block.get("zero_sd")
        added = block.get("std_added")
        return cls(
            applied=applied,
            file=file,
            zero_sd=SensorZero.from_json(_object(zero)) if zero is not None else None,
            std_added={k: _float(v) for k, v in _object(added).items()} if added is not None else None,
        )


class DelaySource(StrEnum):
    """Where the wrench delay a recording was compensated by came from."""

    ESTIMATED = "estimated"  # found in the data and resolved
    PARAMETER = "parameter"  # given (`bsp identify --wrench-delay-s`, the node's wrench_delay_s)
    NONE = "none"  # none applied: not resolved, not estimated, or 0 given


@dataclass(frozen=True, kw_only=True)
class DelayBlock:
    """One recording's wrench delay against the markers (a wrench stamped ``t`` was measured at ``t - delay``).

    Attributes
    ----------
    wrench_delay_s, wrench_delay_std_s : the delay compensated and its std, s (std 0 where given or unknown).
    source : estimated, parameter or none.
    estimated_delay_s, estimated_delay_std_s : where estimated, the estimate and its std, s, even where it was
        too small to apply; None where not estimated.
    """

    wrench_delay_s: float
    wrench_delay_std_s: float
    source: DelaySource
    estimated_delay_s: float | None = None
    estimated_delay_std_s: float | None = None

    def to_json(self) -> dict[str, object]:
        """``{"wrench_delay_s", "wrench_delay_std_s", "source"}``, and the estimate where there is one."""
        out: dict[str, object] = {
            "wrench_delay_s": self.wrench_delay_s,
            "wrench_delay_std_s": self.wrench_delay_std_s,
            "source": str(self.source),
        }
        if self.estimated_delay_s is not None:
            out["estimated_delay_s"] = self.estimated_delay_s
            out["estimated_delay_std_s"] = self.estimated_delay_std_s
        return out

    @classmethod
    def from_json(cls, block: Mapping[str, object]) -> DelayBlock:
        """The delay of one recording's timing block."""
        estimated = block.get("estimated_delay_s")
        return cls(
            wrench_delay_s=_float(block["wrench_delay_s"]),
            wrench_delay_std_s=_float(block["wrench_delay_std_s"]),
            source=DelaySource(_str(block["source"])),
            estimated_delay_s=_float(estimated) if estimated is not None else None,
            estimated_delay_std_s=_float(block["estimated_delay_std_s"]) if estimated is not None else None,
        )


@dataclass(frozen=True, kw_only=True)
class TimingBlock:
    """``quality.timing``: the wrench delay of each recording identified (one: the block is that recording's;
    several: ``{"recordings": [...]}``)."""

    recordings: tuple[DelayBlock, ...]

    @property
    def delay(self) -> DelayBlock:
        """The first (for one recording: the) recording's delay."""
        return self.recordings[0]

    def to_json(self) -> dict[str, object]:
        """One recording's delay block, or ``{"recordings": [...]}`` for several."""
        if len(self.recordings) == 1:
            return self.recordings[0].to_json()
        return {"recordings": [r.to_json() for r in self.recordings]}

    @classmethod
    def from_json(cls, block: Mapping[str, object]) -> TimingBlock:
        """The timing of a ``quality.timing`` block."""
        if "recordings" in block:
            return cls(recordings=tuple(DelayBlock.from_json(_object(r)) for r in _list(block["recordings"])))
        return cls(recordings=(DelayBlock.from_json(block),))


@dataclass(frozen=True, kw_only=True)
class RotationBlock:
    """``quality.rotation``: where the wrench frame's rotation to ``world`` came from and how much it varied.

    Attributes
    ----------
    sources : ``tf``, ``topic``, ``alias``, ``cell``, ``metadata`` or ``assumed`` (a bag's ``rotation_source``), one
        per distinct source of the recordings in order, or ``session`` before a bag read names it; the JSON's
        ``source`` joins them with ``, ``.
    per_sample : the rotation was known per wrench sample (a turning sensor), not one fixed rotation.
    range_deg : the largest angle between two of its rotations, deg.
    """

    sources: tuple[str, ...]
    per_sample: bool
    range_deg: float

    @property
    def source(self) -> str:
        """The JSON's ``source``: the sources joined by ``, ``."""
        return ", ".join(self.sources)

    def with_source(self, source: str, *, appended: bool) -> RotationBlock:
        """This block with ``source`` in place of its sources, or (``appended``) after them where new."""
        sources = (*self.sources, source) if appended else (source,)
        return replace(self, sources=tuple(dict.fromkeys(sources)))

    def to_json(self) -> dict[str, object]:
        """``{"source", "per_sample", "range_deg"}``."""
        return {"source": self.source, "per_sample": self.per_sample, "range_deg": self.range_deg}

    @classmethod
    def from_json(cls, block: Mapping[str, object]) -> RotationBlock:
        """The rotation block of a document."""
        source, per_sample = block["source"], block["per_sample"]
        if not isinstance(source, str) or not isinstance(per_sample, bool):
            raise TypeError(f"quality.rotation: source must be a string and per_sample a bool, got {dict(block)!r:.80}")
        return cls(sources=tuple(source.split(", ")), per_sample=per_sample, range_deg=_float(block["range_deg"]))


@dataclass(frozen=True, kw_only=True)
class PlacementBlock:
    """``quality.marker_placement``: the skin markers' placement off their joint centres that the std holds.

    Attributes
    ----------
    assumed_sd_mm : per chain point (shoulder to contact point) the placement assumed, mm (1 SD per axis).
    sd_mm : per chain point the placement the std holds, mm: the assumed one times ``scale_from_data``.
    scale_from_data : the scale the data support (>= 1, at most 10).
    likelihood_ratio : the evidence of the most likely scale against the assumed one.
    scale_most_likely : the single most likely scale.
    """

    assumed_sd_mm: tuple[float, ...]
    sd_mm: tuple[float, ...]
    scale_from_data: float
    likelihood_ratio: float
    scale_most_likely: float

    def to_json(self) -> dict[str, object]:
        """The block in docs/contract.md's key order."""
        return {
            "assumed_sd_mm": list(self.assumed_sd_mm),
            "sd_mm": list(self.sd_mm),
            "scale_from_data": self.scale_from_data,
            "likelihood_ratio": self.likelihood_ratio,
            "scale_most_likely": self.scale_most_likely,
        }

    @classmethod
    def from_json(cls, block: Mapping[str, object]) -> PlacementBlock:
        """The placement block of a document."""
        return cls(
            assumed_sd_mm=tuple(_float(v) for v in _list(block["assumed_sd_mm"])),
            sd_mm=tuple(_float(v) for v in _list(block["sd_mm"])),
            scale_from_data=_float(block["scale_from_data"]),
            likelihood_ratio=_float(block["likelihood_ratio"]),
            scale_most_likely=_float(block["scale_most_likely"]),
        )


@dataclass(frozen=True, kw_only=True)
class BagSection:
    """The ``bag`` section: what the read of one bag found (one entry of ``bags`` for several recordings).

    Attributes
    ----------
    files : the MCAP files read, by name, in order.
    messages : per topic the messages read.
    lost_messages : messages the bag's summary counts that could not be read; None where unknown (no summary).
    crc_errors : chunks whose CRC did not match.
    truncated : a file ended before its footer.
    chunks_without_crc : chunks written without a CRC (damage there cannot be detected).
    rotation_source : where the wrench frame's rotation came from (``tf``, ``topic``, ``alias``, ``cell``,
        ``metadata``, ``assumed``).
    damage : one line per damaged place.
    implausible_samples_removed : samples implausible in themselves (the signature of bit damage), by kind.
    """

    files: tuple[str, ...]
    messages: Mapping[str, int]
    lost_messages: int | None
    crc_errors: int
    truncated: bool
    chunks_without_crc: int
    rotation_source: str
    damage: tuple[str, ...]
    implausible_samples_removed: Mapping[str, int]

    def to_json(self) -> dict[str, object]:
        """The section in the order the bag reader writes it."""
        return {
            "files": list(self.files),
            "messages": dict(self.messages),
            "lost_messages": self.lost_messages,
            "crc_errors": self.crc_errors,
            "truncated": self.truncated,
            "chunks_without_crc": self.chunks_without_crc,
            "rotation_source": self.rotation_source,
            "damage": list(self.damage),
            "implausible_samples_removed": dict(self.implausible_samples_removed),
        }

    @classmethod
    def from_json(cls, block: Mapping[str, object]) -> BagSection:
        """The bag section of a document."""
        lost = block["lost_messages"]
        return cls(
            files=tuple(_str(f) for f in _list(block["files"])),
            messages={k: _int(v) for k, v in _object(block["messages"]).items()},
            lost_messages=_int(lost) if lost is not None else None,
            crc_errors=_int(block["crc_errors"]),
            truncated=_bool(block["truncated"]),
            chunks_without_crc=_int(block["chunks_without_crc"]),
            rotation_source=_str(block["rotation_source"]),
            damage=tuple(_str(d) for d in _list(block["damage"])),
            implausible_samples_removed={k: _int(v) for k, v in _object(block["implausible_samples_removed"]).items()},
        )


def _float(value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(f"not a number: {value!r:.40}")
    return float(value)


def _int(value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"not an integer: {value!r:.40}")
    return value


def _bool(value: object) -> bool:
    if not isinstance(value, bool):
        raise TypeError(f"not true or false: {value!r:.40}")
    return value


def _str(value: object) -> str:
    if not isinstance(value, str):
        raise TypeError(f"not a string: {value!r:.40}")
    return value


def _list(value: object) -> list[object]:
    if not isinstance(value, list):
        raise TypeError(f"not a list: {value!r:.40}")
    return value


def _object(value: object) -> Mapping[str, object]:
    if not isinstance(value, Mapping) or not all(isinstance(k, str) for k in value):
        raise TypeError(f"not an object: {value!r:.40}")
    return value
