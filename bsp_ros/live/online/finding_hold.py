"""A model check's finding held through one live check that misses it: consecutive windows share most samples."""

from __future__ import annotations

import dataclasses

from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.result import IdentificationResult

__all__ = ["FindingHold"]

# Checks in a row that must miss a finding before it is cleared.
CLEAR_AFTER = 2

HELD_NOTE = Finding(code=FindingCode.HELD_FROM_CHECK)


class FindingHold:
    """Holds what a live window's model checks found the model lacks (an elastic moment, Stribeck-like friction, an
    implausible off-axis moment) until ``CLEAR_AFTER`` checks in a row miss it.

    A 30 s window checked every 5 s shares 25 s with the window before. Over such windows an elbow spring of 1.2
    Nm/rad was found at p 1e-20 to 1e-139 by eleven checks and missed by two between them (p 7e-4 and 0.12: the
    spring and gravity nearly one in those 30 s), whose refits held a valid estimate 6 std off for 5 s each
    (``bench/live_realism.py``). A finding that vanishes from one check to the next is likelier a dip of the test's
    power than a change of the arm.
    """

    def __init__(self) -> None:
        self.findings: tuple[Finding, ...] = ()
        self._missed = 0

    def reset(self) -> None:
        """Forget the findings (the window's samples were cleared: a new arm or session may follow)."""
        self.findings, self._missed = (), 0

    def checked(self, result: IdentificationResult) -> IdentificationResult:
        """One check's ``result`` (with its ``held`` model), invalid with the held findings while they hold."""
        held = result.held
        if held is None:
            return result
        if held.check_problems:
            self.findings, self._missed = held.check_problems, 0
            return result
        if not self.findings or held.data_problems:
            return result  # nothing held, or samples that support no estimate (their own verdict)
        self._missed += 1
        if self._missed >= CLEAR_AFTER:
            self.reset()
            return result
        return dataclasses.replace(
            result,
            findings=(*self.findings, *result.findings, HELD_NOTE),
            held=dataclasses.replace(held, check_problems=self.findings),
        )
