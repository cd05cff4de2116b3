"""Two-sided calibration and sharpness of reported stds against a simulation's truth.

Valid-and-wrong counts only stds that are too narrow; a std a hundred times too wide passes it. These metrics
catch both sides:

- z RMS over the parameters of valid estimates, ``z = (estimate - truth) / std``: 1 for an honest std, below 1
  for a std too wide, above 1 for one too narrow;
- the share within 1 and within 2 std: 68.3 % and 95.4 % for an honest (normal) std;
- sharpness of one parameter over repeated sessions of one arm: the median reported std over the RMS error
  across the sessions (1 is ideal; 10 means the std is ten times wider than the errors it should describe),
  summarized per parameter kind (static moments, Coulomb amplitudes, masses) as median and range.

Parameters are named ``quantity/owner`` (``static_moment_kgm/upper_arm``) as :func:`scoring.residuals` names
them. Pure functions of numbers (numpy only), so that the unit tests import this module without the estimator.
"""

from __future__ import annotations

import dataclasses
import math
from collections import defaultdict
from collections.abc import Iterable, Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

# The share of a standard normal within 1 and 2 std: what an honest std gives.
HONEST_WITHIN_1 = 0.6827
HONEST_WITHIN_2 = 0.9545

# Parameter kinds whose sharpness is printed, by the quantity key of the estimate document.
KINDS: dict[str, str] = {
    "static_moment_kgm": "static moments",
    "coulomb_nm": "Coulomb amplitudes",
    "mass_kg": "masses",
}
# Short column labels of :data:`KINDS`, same order, for tables.
KIND_LABELS: dict[str, str] = {
    "static moments": "sharp SM",
    "Coulomb amplitudes": "sharp C",
    "masses": "sharp m",
}


@dataclasses.dataclass(frozen=True)
class Calibration:
    """Two-sided calibration of a set of z values.

    Attributes
    ----------
    count : int
        Number of z values (parameters x estimates).
    z_rms : float
        ``sqrt(mean(z ** 2))``; 1 for an honest std, NaN without values, infinite if some std was 0 and its
        estimate not exact.
    within_1, within_2, within_3 : float
        Share (0-1) of ``|z| <= 1``, ``<= 2``, ``<= 3``; NaN without values.
    """

    count: int
    z_rms: float
    within_1: float
    within_2: float
    within_3: float


@dataclasses.dataclass(frozen=True)
class Spread:
    """Median and range of one parameter kind's sharpness over its parameters.

    Attributes
    ----------
    count : int
        Parameters with a sharpness (enough sessions, a nonzero RMS error).
    median, low, high : float
        Median, smallest and largest sharpness (dimensionless, 1 ideal); NaN if ``count`` is 0.
    """

    count: int
    median: float
    low: float
    high: float


def z_values(residuals: Mapping[str, tuple[float, float]]) -> dict[str, float]:
    """Signed z of each parameter from its error and std.

    Parameters
    ----------
    residuals : mapping
        ``name -> (estimate - truth, std)``, both in the parameter's unit.

    Returns
    -------
    dict
        ``name -> z = error / std`` (dimensionless); a zero std gives 0 if the error is 0, else +-infinity.
    """
    out = {}
    for name, (error, std) in residuals.items():
        if std:
            out[name] = float(error) / float(std)
        else:
            out[name] = 0.0 if error == 0.0 else math.copysign(math.inf, float(error))
    return out


def calibration(z: ArrayLike) -> Calibration:
    """z RMS and the shares within 1, 2 and 3 std of signed (or absolute) z values.

    Parameters
    ----------
    z : array_like, shape (n,)
        z values, ``(estimate - truth) / std``, of every parameter of every estimate scored. NaN entries
        (no value) are left out; infinite ones are kept (a zero std with an inexact estimate).

    Returns
    -------
    Calibration
    """
    values = np.asarray(z, dtype=float).ravel()
    values = np.abs(values[~np.isnan(values)])
    if values.size == 0:
        return Calibration(0, math.nan, math.nan, math.nan, math.nan)
    return Calibration(
        count=int(values.size),
        z_rms=float(np.sqrt(np.mean(values**2))),
        within_1=float(np.mean(values <= 1.0)),
        within_2=float(np.mean(values <= 2.0)),
        within_3=float(np.mean(values <= 3.0)),
    )


def sharpness(errors: ArrayLike, stds: ArrayLike) -> float:
    """One parameter's median reported std over its RMS error across repeated sessions.

    Parameters
    ----------
    errors : array_like, shape (n,)
        ``estimate - truth`` of the parameter in each of ``n`` sessions (its unit).
    stds : array_like, shape (n,)
        The std reported with each estimate (same unit).

    Returns
    -------
    float
        ``median(stds) / sqrt(mean(errors ** 2))`` (dimensionless): 1 ideal, above 1 a std too wide, below 1 a
        std too narrow. NaN with fewer than 2 sessions (one error says little about their spread) or when every
        error is 0 (no scale to compare with).
    """
    e = np.asarray(errors, dtype=float).ravel()
    s = np.asarray(stds, dtype=float).ravel()
    if e.shape != s.shape:
        raise ValueError(f"errors {e.shape} and stds {s.shape} differ in shape")
    keep = np.isfinite(e) & np.isfinite(s)
    e, s = e[keep], s[keep]
    rms = float(np.sqrt(np.mean(e**2))) if e.size else 0.0
    if e.size < 2 or rms == 0.0:
        return math.nan
    return float(np.median(s)) / rms


def quantity(name: str) -> str:
    """The quantity key of a parameter named ``quantity/owner`` (``static_moment_kgm/forearm`` -> its first part)."""
    return name.split("/", 1)[0]


def spread(values: Iterable[float]) -> Spread:
    """Median and range of the finite values (e.g. one kind's sharpness over its parameters).

    Parameters
    ----------
    values : iterable of float

    Returns
    -------
    Spread
    """
    finite = np.array([v for v in values if math.isfinite(v)], dtype=float)
    if finite.size == 0:
        return Spread(0, math.nan, math.nan, math.nan)
    return Spread(int(finite.size), float(np.median(finite)), float(finite.min()), float(finite.max()))


def sharpness_by_kind(
    samples: Mapping[str, Sequence[tuple[float, float]]], kinds: Mapping[str, str] = KINDS
) -> dict[str, Spread]:
    """Sharpness of every parameter, summarized per kind.

    Parameters
    ----------
    samples : mapping
        ``quantity/owner -> [(estimate - truth, std), ...]``, one pair per session of the same arm.
    kinds : mapping
        ``quantity key -> kind name``; parameters of other quantities are left out.

    Returns
    -------
    dict
        ``kind name -> Spread`` of its parameters' :func:`sharpness`, for every kind in ``kinds`` (in that order).
    """
    per_kind: dict[str, list[float]] = defaultdict(list)
    for name, pairs in samples.items():
        kind = kinds.get(quantity(name))
        if kind is None or not pairs:
            continue
        errors, stds = zip(*pairs, strict=True)
        per_kind[kind].append(sharpness(errors, stds))
    return {kind: spread(per_kind.get(kind, ())) for kind in kinds.values()}


class Tally:
    """Collects the residuals of one table row's estimates; gives its calibration and sharpness.

    Only valid estimates count: an invalid one tells the user not to use its numbers (the error rates judge it).
    Sharpness assumes the row's sessions are of one arm (its truths the same), else it mixes arms.
    """

    def __init__(self) -> None:
        self.z: list[float] = []
        self.samples: dict[str, list[tuple[float, float]]] = defaultdict(list)

    def add(self, residuals: Mapping[str, tuple[float, float]], valid: bool = True) -> None:
        """Add one estimate.

        Parameters
        ----------
        residuals : mapping
            ``quantity/owner -> (estimate - truth, std)`` of its scored parameters.
        valid : bool
            The estimate's validity; an invalid estimate is not added.
        """
        if not valid:
            return
        self.z.extend(z_values(residuals).values())
        for name, pair in residuals.items():
            self.samples[name].append((float(pair[0]), float(pair[1])))

    def extend(self, other: Tally) -> None:
        """Add every estimate of another tally (a total over rows)."""
        self.z.extend(other.z)
        for name, pairs in other.samples.items():
            self.samples[name].extend(pairs)

    def calibration(self) -> Calibration:
        """:func:`calibration` of every z added."""
        return calibration(self.z)

    def sharpness(self, kinds: Mapping[str, str] = KINDS) -> dict[str, Spread]:
        """:func:`sharpness_by_kind` of every parameter added."""
        return sharpness_by_kind(self.samples, kinds)


def calibration_header() -> str:
    """Column titles matching :func:`calibration_columns`."""
    return f"{'zRMS':>6s} {'in1sd':>5s} {'in2sd':>5s}"


def calibration_columns(c: Calibration) -> str:
    """z RMS and the shares within 1 and 2 std as fixed-width columns (``-`` without values)."""
    if c.count == 0:
        return f"{'-':>6s} {'-':>5s} {'-':>5s}"
    return f"{c.z_rms:6.3g} {100 * c.within_1:4.0f}% {100 * c.within_2:4.0f}%"


SHARPNESS_WIDTH = 18


def _short(value: float, digits: int) -> str:
    """``value`` to ``digits`` significant digits without an exponent between 1e-4 and 1e6 (1400, not 1.4e+03)."""
    return f"{float(f'{value:.{digits}g}'):g}"


def sharpness_header(kinds: Mapping[str, str] = KINDS) -> str:
    """Column titles matching :func:`sharpness_columns`."""
    return " ".join(f"{KIND_LABELS.get(k, k[:SHARPNESS_WIDTH]):>{SHARPNESS_WIDTH}s}" for k in kinds.values())


def format_spread(s: Spread) -> str:
    """``median (low-high)``, or ``-`` without values, each to three significant digits (fewer would round the
    range past the median)."""
    if s.count == 0:
        return "-"
    if s.count == 1:
        return _short(s.median, 3)
    return f"{_short(s.median, 3)} ({_short(s.low, 3)}-{_short(s.high, 3)})"


def sharpness_columns(spreads: Mapping[str, Spread], kinds: Mapping[str, str] = KINDS) -> str:
    """Each kind's sharpness as median (range), fixed-width, in the order of ``kinds`` (``-`` where missing)."""
    empty = Spread(0, math.nan, math.nan, math.nan)
    return " ".join(f"{format_spread(spreads.get(k, empty)):>{SHARPNESS_WIDTH}s}" for k in kinds.values())


def summary_line(label: str, tally: Tally, sharpness: bool = True) -> str:
    """One line of a tally's figures: z RMS, shares within 1/2/3 std and (``sharpness``) each kind's sharpness.

    Parameters
    ----------
    label : str
        What the line is about (printed first).
    tally : Tally
        The estimates.
    sharpness : bool
        Give the sharpness too; leave it out where the tally mixes arms or nuisances.

    Returns
    -------
    str
    """
    c = tally.calibration()
    if c.count == 0:
        return f"{label}: no valid estimate scored"
    line = (
        f"{label}: {c.count} parameters of valid estimates, z RMS {c.z_rms:.3g} (honest 1), within 1 std "
        f"{100 * c.within_1:.1f} % (honest 68.3), within 2 std {100 * c.within_2:.1f} % (95.4), within 3 std "
        f"{100 * c.within_3:.1f} %"
    )
    if sharpness:
        kinds = "; ".join(f"{kind} {format_spread(s)}" for kind, s in tally.sharpness().items())
        line += f"; sharpness, median std / RMS error per parameter (1 ideal): {kinds}"
    return line
