"""Whether a live session is precise enough: every parameter it is for within its target relative std, held.

The robot's session logic and the therapist want one signal, "this session has measured what it was for", that
does not flicker: a windowed estimate's std wanders with the motion inside the window, and a signal that came and
went with it would stop and restart a protocol. So the signal comes once every targeted parameter of valid
estimates has stayed within its target for ``hold_s`` (the estimates' node clock), and then stays for the rest of
the session: until the inputs stop for ``session_gap_s`` (the session ended) or the estimate restarts.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.findings import FindingCode

__all__ = [
    "SESSION_GAP_S",
    "ParameterPrecision",
    "PrecisionState",
    "PrecisionTarget",
    "PrecisionTracker",
]

#: Inputs stopped this long end a session (as `session_recorder`'s default ``end_timeout_s``), s.
SESSION_GAP_S = 5.0
#: Verdicts that say the identifier's inputs stopped or have not started: no session runs.
_STOPPED = frozenset({FindingCode.INPUT_STALE, FindingCode.INPUT_WAITING})


@dataclass(frozen=True, kw_only=True)
class PrecisionTarget:
    """What a session is for: the largest relative std (std / |value|, a fraction) of each parameter, and the hold.

    Attributes
    ----------
    relative_std : ``{(owner, quantity key): largest relative std}``, e.g. ``{("forearm", "static_moment_kgm"):
        0.05}``; at least one entry, each a finite fraction above 0.
    hold_s : how long every parameter must stay within its target before the signal comes, s (>= 0).
    session_gap_s : inputs stopped this long end the session and clear the signal, s (> 0).
    """

    relative_std: Mapping[tuple[str, str], float]
    hold_s: float
    session_gap_s: float = SESSION_GAP_S

    def __post_init__(self) -> None:
        if not self.relative_std:
            raise ValueError("a precision target needs at least one parameter")
        for (owner, key), limit in self.relative_std.items():
            if not (math.isfinite(limit) and limit > 0):
                raise ValueError(f"target relative std of {owner} {key} must be finite and > 0, got {limit!r}")
        if not (math.isfinite(self.hold_s) and self.hold_s >= 0):
            raise ValueError(f"hold_s must be finite and >= 0, got {self.hold_s!r}")
        if not (math.isfinite(self.session_gap_s) and self.session_gap_s > 0):
            raise ValueError(f"session_gap_s must be finite and > 0, got {self.session_gap_s!r}")

    @classmethod
    def static_moments(
        cls, percent: float, segments: Sequence[str], hold_s: float, session_gap_s: float = SESSION_GAP_S
    ) -> PrecisionTarget:
        """Every segment's static moment within ``percent`` % relative std (what a weight support needs)."""
        limits = {(segment, "static_moment_kgm"): percent / 100.0 for segment in segments}
        return cls(relative_std=limits, hold_s=hold_s, session_gap_s=session_gap_s)


@dataclass(frozen=True, kw_only=True)
class ParameterPrecision:
    """One targeted parameter in one estimate.

    Attributes
    ----------
    owner, quantity : the segment or joint and the quantity key (``static_moment_kgm``).
    relative_std : std / |value| (fraction), or None where the estimate has no finite value and std for it.
    target : the largest relative std the session is for (fraction).
    """

    owner: str
    quantity: str
    relative_std: float | None
    target: float

    @property
    def within(self) -> bool:
        """Whether the parameter is at or below its target."""
        return self.relative_std is not None and self.relative_std <= self.target

    @property
    def ratio(self) -> float:
        """relative std / target (inf where unknown): how far from its target, 1 at the target."""
        return math.inf if self.relative_std is None else self.relative_std / self.target

    def to_json(self) -> dict[str, Any]:
        """``{"owner", "quantity", "relative_std_percent", "target_percent", "within"}``."""
        relative = None if self.relative_std is None else 100.0 * self.relative_std
        return {
            "owner": self.owner,
            "quantity": self.quantity,
            "relative_std_percent": relative,
            "target_percent": 100.0 * self.target,
            "within": self.within,
        }

    @classmethod
    def from_json(cls, block: Mapping[str, Any]) -> ParameterPrecision:
        """The parameter of a :meth:`to_json` block."""
        relative = block.get("relative_std_percent")
        return cls(
            owner=str(block["owner"]),
            quantity=str(block["quantity"]),
            relative_std=None if relative is None else float(relative) / 100.0,
            target=float(block["target_percent"]) / 100.0,
        )


@dataclass(frozen=True, kw_only=True)
class PrecisionState:
    """The signal after one estimate.

    Attributes
    ----------
    reached : every targeted parameter has stayed within its target for the hold; stays True for the session.
    reached_after_s : session time (from its first estimate with inputs) when it came, s; None before.
    within_s : how long every parameter has now been within its target, s; None while one is not (or the estimate
        is invalid).
    hold_s : the hold the signal waits for, s.
    parameters : each targeted parameter in this estimate.
    """

    reached: bool
    reached_after_s: float | None
    within_s: float | None
    hold_s: float
    parameters: tuple[ParameterPrecision, ...]

    @property
    def worst(self) -> ParameterPrecision | None:
        """The parameter furthest from its target (the largest ratio), or None without parameters."""
        return max(self.parameters, key=lambda p: p.ratio, default=None)

    def to_json(self) -> dict[str, Any]:
        """The estimate JSON's ``precision`` block (docs/contract.md, section 4)."""
        return {
            "reached": self.reached,
            "reached_after_s": self.reached_after_s,
            "within_s": self.within_s,
            "hold_s": self.hold_s,
            "parameters": [p.to_json() for p in self.parameters],
        }

    @classmethod
    def from_json(cls, block: Mapping[str, Any]) -> PrecisionState:
        """The state of a ``precision`` block.

        Raises
        ------
        KeyError, TypeError, ValueError
            A block that is not one (the caller decides what that means).
        """
        after, within = block.get("reached_after_s"), block.get("within_s")
        return cls(
            reached=bool(block["reached"]),
            reached_after_s=None if after is None else float(after),
            within_s=None if within is None else float(within),
            hold_s=float(block["hold_s"]),
            parameters=tuple(ParameterPrecision.from_json(p) for p in block.get("parameters") or ()),
        )


def parameter_precision(estimate: Estimate, owner: str, key: str, target: float) -> ParameterPrecision:
    """How precise one parameter of ``estimate`` is (no finite value and std, or a zero value: unknown)."""
    quantity = estimate.quantity(key, owner)
    relative = None
    if quantity is not None and quantity.finite and quantity.value:
        assert quantity.value is not None and quantity.std is not None  # finite
        relative = quantity.std / abs(quantity.value)
    return ParameterPrecision(owner=owner, quantity=key, relative_std=relative, target=target)


class PrecisionTracker:
    """Turns each live estimate into the session's precision signal (:class:`PrecisionState`).

    Parameters
    ----------
    target : the parameters the session is for, their targets, the hold and the session gap.
    """

    def __init__(self, target: PrecisionTarget) -> None:
        self.target = target
        self.reset()

    def reset(self) -> None:
        """A new session: the signal cleared (the estimate restarted, or the inputs stopped for the gap)."""
        self.session_start_ns: int | None = None
        self.within_since_ns: int | None = None
        self.stopped_since_ns: int | None = None
        self.reached_ns: int | None = None

    def update(self, estimate: Estimate, now_ns: int) -> PrecisionState:
        """The signal after ``estimate``, computed at ``now_ns`` (the node clock, ns)."""
        verdict = estimate.quality.verdict
        if verdict is not None and verdict.code in _STOPPED:
            self._stopped(now_ns)
        else:
            self.stopped_since_ns = None
            if self.session_start_ns is None:
                self.session_start_ns = now_ns
        parameters = tuple(
            parameter_precision(estimate, owner, key, limit) for (owner, key), limit in self.target.relative_std.items()
        )
        if estimate.valid and all(p.within for p in parameters):
            if self.within_since_ns is None:
                self.within_since_ns = now_ns
        else:
            self.within_since_ns = None
        within_s = None if self.within_since_ns is None else (now_ns - self.within_since_ns) / 1e9
        if self.reached_ns is None and within_s is not None and within_s >= self.target.hold_s:
            self.reached_ns = now_ns
        return PrecisionState(
            reached=self.reached_ns is not None,
            reached_after_s=self._session_time_s(self.reached_ns),
            within_s=within_s,
            hold_s=self.target.hold_s,
            parameters=parameters,
        )

    def _stopped(self, now_ns: int) -> None:
        """Inputs stopped or not started: after ``session_gap_s`` of it the session is over."""
        if self.stopped_since_ns is None:
            self.stopped_since_ns = now_ns
        if now_ns - self.stopped_since_ns >= self.target.session_gap_s * 1e9:
            self.reset()
            self.stopped_since_ns = now_ns

    def _session_time_s(self, t_ns: int | None) -> float | None:
        if t_ns is None or self.session_start_ns is None:
            return None
        return (t_ns - self.session_start_ns) / 1e9
