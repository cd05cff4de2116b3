"""Scores an estimate document against a simulation's truth: its data-sourced parameters' errors and |z|, both error
rates (two-sided calibration and sharpness: :mod:`calibration`), and :class:`Counts`, the trust benchmarks' shared
count of them over a table row's sessions."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Mapping
from typing import Any, ClassVar

from calibration import Tally, z_values

DATA_SOURCES = ("data", "data+prior")
# The |z| beyond which a valid estimate is wrong (and within which an invalid one was right).
WRONG_Z = 3.0


def residuals(document: dict[str, Any], truth: dict[str, Any]) -> dict[str, tuple[float, float]]:
    """(value - truth, std) of every data-sourced parameter the truth knows, keyed ``quantity/owner``.

    Parameters
    ----------
    document : dict
        An estimate document (``segments`` and ``joints``, each quantity with ``value``, ``std``, ``source``).
    truth : dict
        The simulation's truth in the same layout (``SimulatedSession.truth.to_dict()``, truth.json).

    Returns
    -------
    dict
        ``quantity/owner -> (signed error, std)`` in the quantity's unit; a missing std is 0. Invalid estimates
        are scored too (their values are what a user who ignored the flag would take); a parameter without a
        value is left out.
    """
    out = {}
    for group in ("segments", "joints"):
        for owner, quantities in document.get(group, {}).items():
            for key, q in quantities.items():
                if not isinstance(q, dict) or q.get("source") not in DATA_SOURCES:
                    continue
                true = truth.get(group, {}).get(owner, {}).get(key)
                value, std = q.get("value"), q.get("std")
                if not isinstance(true, (int, float)) or value is None:
                    continue
                out[f"{key}/{owner}"] = (float(value) - float(true), float(std or 0.0))
    return out


def z_scores(document: dict[str, Any], truth: dict[str, Any]) -> dict[str, float]:
    """|value - truth| / std of every parameter :func:`residuals` scores, keyed ``quantity/owner``.

    A parameter with a zero or missing std scores 0 if exact, else infinity.
    """
    return {name: abs(z) for name, z in z_values(residuals(document, truth)).items()}


def verdict(valid: bool, max_z: float) -> str:
    """``valid-and-wrong`` (valid, some |z| > 3), ``invalid-and-right`` (invalid, every |z| <= 3), else ``ok``."""
    if math.isnan(max_z):
        return "ok"
    if valid and max_z > WRONG_Z:
        return "valid-and-wrong"
    if not valid and max_z <= WRONG_Z:
        return "invalid-and-right"
    return "ok"


def rates(verdicts: Iterable[str]) -> tuple[int, int, int]:
    """(runs, valid-and-wrong, invalid-and-right) of a list of :func:`verdict` results."""
    items = list(verdicts)
    return len(items), items.count("valid-and-wrong"), items.count("invalid-and-right")


@dataclasses.dataclass(frozen=True, kw_only=True)
class Scored:
    """One estimate scored against its truth.

    Attributes
    ----------
    valid : bool
        The estimate's validity (``quality.valid``).
    z : mapping
        ``name -> |z|`` (dimensionless) of every parameter scored; a benchmark may score more than ``residuals``
        holds (the musculoskeletal one its passive curves' worst points).
    residuals : mapping
        ``quantity/owner -> (estimate - truth, std)``, each in its quantity's unit: what the two-sided calibration
        takes.
    """

    valid: bool
    z: Mapping[str, float]
    residuals: Mapping[str, tuple[float, float]]

    @classmethod
    def from_residuals(cls, valid: bool, residuals: Mapping[str, tuple[float, float]]) -> Scored:
        """The estimate of these :func:`residuals`, its |z| theirs (as :func:`z_scores` gives them)."""
        return cls(valid=valid, z={name: abs(z) for name, z in z_values(residuals).items()}, residuals=residuals)

    @property
    def worst(self) -> str:
        """The parameter of the largest |z| (the first of equal ones); ``""`` without a scored parameter."""
        return max(self.z, key=lambda name: self.z[name]) if self.z else ""

    @property
    def max_z(self) -> float:
        """The largest |z|; NaN without a scored parameter."""
        return self.z[self.worst] if self.z else math.nan

    @property
    def wrong(self) -> bool:
        """Some |z| beyond :data:`WRONG_Z`."""
        return self.max_z > WRONG_Z

    @property
    def verdict(self) -> str:
        """:func:`verdict` of the estimate: an estimate without a scored parameter is ``ok``."""
        return verdict(self.valid, self.max_z)


def scored(estimate: dict[str, Any], truth: dict[str, Any]) -> Scored:
    """An estimate document scored against the truth: its validity and every parameter :func:`residuals` scores."""
    return Scored.from_residuals(bool(estimate["quality"]["valid"]), residuals(estimate, truth))


@dataclasses.dataclass(kw_only=True)
class Counts:
    """Both error rates over the sessions of one table row, their worst |z| and their two-sided calibration.

    A benchmark's row derives from it (or holds one) and adds its own columns: reasons, codes, scales.

    Attributes
    ----------
    runs : int
        Sessions counted, those that gave no estimate (``failed``) included.
    failed : int
        Sessions that gave no estimate (the tool's exit code was all there was).
    valid : int
        Valid estimates.
    valid_wrong, invalid_right : int
        Estimates whose :attr:`Scored.verdict` is ``valid-and-wrong``, ``invalid-and-right``.
    worst_z : float
        The largest |z| of any estimate counted, valid or not (0 before one with a |z| above 0).
    worst_param : str
        Its parameter (``""`` before then).
    two_sided : calibration.Tally
        The residuals of the valid estimates (z RMS, shares within 1 and 2 std, sharpness).
    """

    # Whether an invalid estimate without a scored parameter counts as invalid-and-right: every |z| <= 3 holds
    # for it vacuously. Off, it is ``ok`` as :func:`verdict` has it.
    UNSCORED_INVALID_RIGHT: ClassVar[bool] = False

    runs: int = 0
    failed: int = 0
    valid: int = 0
    valid_wrong: int = 0
    invalid_right: int = 0
    worst_z: float = 0.0
    worst_param: str = ""
    two_sided: Tally = dataclasses.field(default_factory=Tally)

    def count(self, run: Scored) -> Scored:
        """Count one scored estimate; return it (its verdict, worst |z|... for the benchmark's own columns)."""
        self.runs += 1
        self.valid += run.valid
        outcome = run.verdict
        if not run.z and not run.valid and self.UNSCORED_INVALID_RIGHT:
            outcome = "invalid-and-right"
        self.valid_wrong += outcome == "valid-and-wrong"
        self.invalid_right += outcome == "invalid-and-right"
        if run.z and run.max_z > self.worst_z:
            self.worst_z, self.worst_param = run.max_z, run.worst
        self.two_sided.add(run.residuals, run.valid)
        return run

    def score(self, estimate: dict[str, Any], truth: dict[str, Any]) -> Scored:
        """Count an estimate document scored against the truth (:func:`scored`); return its score."""
        return self.count(scored(estimate, truth))

    def count_failure(self) -> None:
        """Count a session that gave no estimate."""
        self.runs += 1
        self.failed += 1

    def pool(self, other: Counts) -> None:
        """Add ``other``'s counts, worst |z| and residuals (a total over rows).

        The pooled residuals' sharpness mixes the rows' arms and nuisances: read only their calibration.
        """
        self.runs += other.runs
        self.failed += other.failed
        self.valid += other.valid
        self.valid_wrong += other.valid_wrong
        self.invalid_right += other.invalid_right
        if other.worst_z > self.worst_z:
            self.worst_z, self.worst_param = other.worst_z, other.worst_param
        self.two_sided.extend(other.two_sided)

    def counts_json(self) -> dict[str, int]:
        """``runs``, ``valid``, ``valid_wrong``, ``invalid_right`` for a benchmark's JSON."""
        return {name: getattr(self, name) for name in ("runs", "valid", "valid_wrong", "invalid_right")}
