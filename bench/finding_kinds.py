"""Findings as the benches count them: each one's code with its joint or segment (``model_misfit elbow``).

A bench that tallies why estimates were invalid, or which warnings fired, groups them by these kinds: alike
findings count together whatever their numbers, and nothing is read out of a rendered message.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from bsp_ros.core.findings import Finding, Severity, findings_of, verdict_of

NO_FINDING = "(no finding)"


def kind_of(finding: Finding) -> str:
    """A finding's code and, where it has one, its joint or segment: ``"model_misfit elbow"``, ``"prior_note"``."""
    return f"{finding.code} {finding.where}".strip()


def cause_of(quality: Mapping[str, Any]) -> str:
    """Why an estimate is invalid: the kind of its first invalid finding (the likeliest cause of the others).

    Parameters
    ----------
    quality : Mapping[str, Any]
        An estimate document's ``quality`` block (docs/contract.md section 4).

    Returns
    -------
    str
        :func:`kind_of` the verdict, or :data:`NO_FINDING` where no finding makes the estimate invalid (a document
        without findings, or one only a newer version's codes make invalid).
    """
    verdict = verdict_of(findings_of(quality))
    return NO_FINDING if verdict is None else kind_of(verdict)


def warning_kinds(quality: Mapping[str, Any]) -> list[str]:
    """The kinds of the findings that qualify or annotate an estimate (its ``warnings``: weak and note), in order."""
    return [kind_of(f) for f in findings_of(quality) if f.severity is not Severity.INVALID]


def passive_options(quality: Mapping[str, Any]) -> list[str]:
    """The ``--passive`` models an estimate's findings name (``values["passive_option"]``), in their order."""
    return [str(f.values["passive_option"]) for f in findings_of(quality) if "passive_option" in f.values]
