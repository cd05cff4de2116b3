"""When a live session ends, which estimate to keep: the last valid one, stored exactly once."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bsp_ros.core.findings import FindingCode, findings_of, verdict_of

# Findings of `bsp_identifier` that mean its inputs stopped or have not started (BspIdentifierNode.stale_reason).
INPUT_STOPPED = frozenset({FindingCode.INPUT_STALE, FindingCode.INPUT_WAITING, FindingCode.WAITING_FOR_CHECK})


@dataclass
class SessionEndDetector:
    """Tracks the live estimates of a session and says when to store its final valid estimate.

    A session ends when estimates stop arriving for ``end_timeout_s`` (or arrive only to say that their
    inputs stopped) or an end-of-session message arrives.
    The final valid estimate is handed out once. A later valid estimate opens a new session only if it is
    built on data after the stored one (``session.start_time_ns`` past the stored ``end_time_ns``): the
    identifier goes on publishing the old session's estimate until its inputs turn stale.
    """

    end_timeout_s: float = 5.0
    last_valid: dict[str, Any] | None = None
    last_seen_ns: int | None = None
    stored: bool = False
    stored_document: dict[str, Any] | None = None

    def _belongs_to_stored_session(self, document: dict[str, Any]) -> bool:
        if self.stored_document is None:
            return False
        start = document.get("session", {}).get("start_time_ns")
        stored_end = self.stored_document.get("session", {}).get("end_time_ns")
        if isinstance(start, int) and isinstance(stored_end, int):
            return start <= stored_end
        return document == self.stored_document

    def on_estimate(self, document: dict[str, Any], now_ns: int) -> None:
        """Remember a live estimate (only valid ones can be stored).

        An estimate the identifier marks as built on stale or missing input says the streams stopped: it
        counts as silence, not as activity.
        """
        quality = document.get("quality") if isinstance(document, dict) else None
        found = findings_of(quality) if isinstance(quality, dict) else []
        verdict = verdict_of(found)
        if verdict is None or verdict.code not in INPUT_STOPPED:
            self.last_seen_ns = now_ns
        if isinstance(document, dict) and isinstance(quality := document.get("quality"), dict) and quality.get("valid"):
            if self.stored:
                if self._belongs_to_stored_session(document):
                    return
                self.stored = False  # a new session after a stored one
            self.last_valid = document

    def due(self, now_ns: int, end_requested: bool = False) -> dict[str, Any] | None:
        """The estimate to store now, or None; each session's estimate is returned at most once."""
        if self.stored or self.last_valid is None or self.last_seen_ns is None:
            return None
        if end_requested or now_ns - self.last_seen_ns > self.end_timeout_s * 1e9:
            self.stored = True
            document, self.last_valid = self.last_valid, None
            self.stored_document = document
            return document
        return None
