"""The recursive mode's estimate held to its window's checked estimate: the std and the verdict the filter lacks."""

from __future__ import annotations

from typing import Any

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode, Severity, findings_of
from bsp_ros.core.identification.ledger import Term
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.live.online.windowed import WindowedIdentifier, WindowEstimate

# The windowed estimate of the recursive mode's window is checked this often (updates of the 5 Hz timer: 10 s).
# Each check refits the window several times while the wrenches wait: this rarely, the wrenches it delays stay a
# share below what the recursive mode's latency p99 counts (bench/README.md, live latency).
CHECK_EVERY = 50

_GROUP = {"static_moment_kgm": "segments"}  # every other parameter of the filter is a joint's passive term


def checked_result(result: IdentificationResult, window: dict[str, Any] | None) -> IdentificationResult:
    """The recursive filter's ``result`` with its window's checked estimate ``window`` (docs/contract.md document).

    The filter's covariance counts the sensor noise only: what the marker placement, the sensor's zero, errors
    correlated along the stream and the friction's shape leave open does not shrink with samples, and the filter's
    std falls far below its error over a session (``bench/live_realism.py --recursive``: the shoulder's Coulomb
    moment 18 std off after 80 s on the clean cell). The window's estimate holds all of those and the model checks'
    verdict: its variances are added to the filter's, and an invalid window makes the filter's estimate invalid with
    its reason. Where the filter's value departs from the window's (its simpler model: the prior's inertias, its own
    dead band and weights), that distance joins the variance too, as the spread between candidate models does
    offline: the filter may be wrong by as much as it disagrees with its checked window.

    Parameters
    ----------
    result : the filter's estimate (``RecursiveIdentifier.result``).
    window : the newest checked window estimate, or None before the first.

    Returns
    -------
    A copy of ``result``, valid only when both are.
    """
    if not result.valid:  # the filter's own verdict first (too few samples, a joint that moved one way)
        return result
    if window is None:
        return result.with_findings(Finding(code=FindingCode.WAITING_FOR_CHECK))
    # The window's findings: its verdict (why it is invalid) and its notes, each once.
    found = [f for f in findings_of(window["quality"]) if f not in result.findings]
    checked = result.with_findings(*found)
    if any(f.severity is Severity.INVALID for f in found):
        return checked
    variance = np.zeros(len(result.names))
    for k, (key, owner) in enumerate(result.names):
        entry = window.get(_GROUP.get(key, "joints"), {}).get(owner, {}).get(key)
        std = entry.get("std") if isinstance(entry, dict) else None
        if std is None or entry.get("value") is None:
            return checked.with_findings(Finding(code=FindingCode.WINDOW_WITHOUT_STD, where=owner, values={"key": key}))
        variance[k] = float(std) ** 2 + (float(result.values[k]) - float(entry["value"])) ** 2
    return checked.plus_term(Term.WINDOW_CHECK, np.diag(variance))


class WindowCheck:
    """The recursive mode's window checks: every ``every`` updates its window (``windowed``, whose estimator runs
    every model check on each call) is identified, and the newest estimate holds the filter's to its std and verdict.
    """

    def __init__(self, windowed: WindowedIdentifier, every: int = CHECK_EVERY) -> None:
        self.windowed = windowed
        self.every = every
        self.document: dict[str, Any] | None = None
        self._since = every  # the first update with a window checks it
        self._epoch = windowed.epoch

    def tick(self, orientation: tuple[str, np.ndarray] | None) -> None:
        """One 5 Hz update: identify the window when due (``orientation``: the wrench's frame and rotation, for the
        sensor zero's share of the std)."""
        self._since += 1
        if self.windowed.epoch != self._epoch:  # the buffers were cleared (a clock jump, a new contact point)
            self._epoch, self.document, self._since = self.windowed.epoch, None, self.every
        if self._since < self.every:
            return
        window = self.windowed.snapshot(orientation=orientation)
        if isinstance(window, WindowEstimate):  # no window yet (waiting, stale): the next update tries again
            return
        self.document = self.windowed.estimate_window(window).document
        self._since = 0

    def checked(self, result: IdentificationResult) -> IdentificationResult:
        """:func:`checked_result` of the filter's ``result`` with the newest checked window."""
        return checked_result(result, self.document)
