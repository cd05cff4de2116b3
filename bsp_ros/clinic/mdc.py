"""Minimal detectable change from test-retest pairs: same subject, same day, the arm re-attached in between."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
import numpy.typing as npt

from bsp_ros.clinic.store.records import ParamKey, SessionRecord

Z95 = 1.96
"""The two-sided 95 % normal quantile of MDC95 = 1.96 x sqrt(2) x SEM."""
MIN_PAIRS = 5
"""Fewer retest pairs give no MDC: the SD of fewer differences is too uncertain to judge changes by."""
DAY_NS = 86_400 * 10**9
POOL_ALPHA = 0.05
"""A subject's own retest pairs are pooled with its cell's unless their variances differ at this level (F-test)."""
RELATIVE_QUANTITIES = ("coulomb_nm", "stiffness_nm_per_rad", "viscous_nms")
"""Positive passive parameters whose day-to-day error grows with their value: judged on the log scale."""


class ErrorScale(StrEnum):
    """The scale a parameter's day-to-day error and its changes are measured on."""

    ABSOLUTE = "absolute"
    """Differences in the parameter's unit."""
    LOG = "log"
    """Differences of natural logarithms: relative changes (0.1 is about 10 %)."""


def scale_of(key: ParamKey) -> ErrorScale:
    """The scale ``key`` is judged on: the log scale for :data:`RELATIVE_QUANTITIES` (their error grows with the
    value: 6-7 % of the friction over a wide range of frictions), else absolute (a quantity that can be 0 or
    negative, such as an elastic offset or a passive moment at one angle)."""
    return ErrorScale.LOG if key[0] == "joints" and key[2] in RELATIVE_QUANTITIES else ErrorScale.ABSOLUTE


RETEST_METHOD = (
    "The minimal detectable change (MDC95) comes from test-retest pairs: the same subject measured twice on "
    "the same day, the arm taken out and re-attached (markers re-placed, strap re-fastened, sensor re-zeroed) in "
    "between. SEM = SD of the retest differences / √2 (the SD taken about zero, so a systematic shift between "
    "test and retest counts as error too); MDC95 = 1.96 × √2 × SEM, where 1.96 is replaced by Student's t "
    "quantile for n degrees of freedom while there are few pairs (n pairs), so a small sample "
    "does not claim changes its own uncertainty could explain. Friction, stiffness and damping are compared as "
    "ratios (differences of their logarithms), because their measurement error grows with their value; the MDC95 "
    "is then a share of the value. A subject's own pairs are used once there are "
    f"at least {MIN_PAIRS}, together with those of every subject measured in the same cell unless the subject's "
    "own spread differently (F-test at 5 %); until then the cell's pairs. The spread of "
    "cycles within one session leaves out everything that differs between days and never judges a change."
)

#: Where a reader of the report finds what its numbers mean (files of the bsp_ros repository).
READING_GUIDE = (
    "What each number means, how to record a retest and what to do about an unusable session: docs/clinic.md "
    "of bsp_ros; the measurement itself: docs/method.md."
)


def mdc95_from_sem(sem: float) -> float:
    """MDC95 = 1.96 x sqrt(2) x SEM: the smallest change between two measurements beyond their 95 % noise."""
    return Z95 * math.sqrt(2.0) * sem


def successive_difference_sem(values: npt.ArrayLike) -> float:
    """SEM of repeated measurements ``values`` (K,) from successive differences; NaN if fewer than 2 finite.

    ``sqrt(sum (x[k+1] - x[k])^2 / (2 (K - 1)))``: for independent repeats of one true value it estimates their
    SD (the difference of two has variance 2 SEM^2), and a slow drift inflates it far less than the plain SD.
    """
    x = np.asarray(values, dtype=np.float64)
    x = x[np.isfinite(x)]
    if x.size < 2:
        return math.nan
    return float(np.sqrt(np.sum(np.diff(x) ** 2) / (2.0 * (x.size - 1))))


def t95(dof: int) -> float:
    """The two-sided 95 % Student t quantile for ``dof`` degrees of freedom (1.96 as dof grows)."""
    from scipy.stats import t

    return float(t.ppf(0.975, dof))


@dataclass(frozen=True)
class RetestPair:
    """A session and its same-day retest (both valid)."""

    test: SessionRecord
    retest: SessionRecord


def retest_pairs(records: Iterable[SessionRecord]) -> list[RetestPair]:
    """Every valid retest with the latest valid non-retest session of the same subject, arm and UTC day before it."""
    ordered = sorted(records, key=lambda r: (r.session_time_ns, r.id or 0))
    pairs = []
    for k, retest in enumerate(ordered):
        if not retest.retest or not retest.quality.valid:
            continue
        day = retest.session_time_ns // DAY_NS
        test = next(
            (
                r
                for r in reversed(ordered[:k])
                if not r.retest
                and r.quality.valid
                and r.subject == retest.subject
                and r.arm == retest.arm
                and r.session_time_ns // DAY_NS == day
            ),
            None,
        )
        if test is not None:
            pairs.append(RetestPair(test, retest))
    return pairs


@dataclass(frozen=True)
class DayToDayError:
    """The measurement error of one parameter between days, from retest pairs.

    Attributes
    ----------
    sem : standard error of measurement (units of the parameter); None with too few pairs.
    mdc95 : the change beyond which a difference between two sessions is more than measurement error.
    n_pairs : retest pairs used; n_subjects : how many subjects they come from.
    icc : ICC(2,1) (absolute agreement) of the pairs where defined (pairs of at least two subjects), else None.
    source : ``subject`` (the subject's own pairs), ``cell`` (every subject of the cell) or ``none``.
    scale : :class:`ErrorScale`; on the log scale ``sem`` and ``mdc95`` are of the natural logarithm of the
        value (unitless: 0.1 is about 10 % of the value), converted to units by :meth:`mdc95_at`.
    """

    sem: float | None
    mdc95: float | None
    n_pairs: int
    n_subjects: int
    icc: float | None
    source: str
    scale: ErrorScale = ErrorScale.ABSOLUTE

    @property
    def known(self) -> bool:
        """Whether changes can be judged against this error."""
        return self.mdc95 is not None

    def mdc95_at(self, value: float | None) -> float | None:
        """The MDC95 in the parameter's unit for a change from ``value`` (a fall on the log scale, the smaller of
        its two directions); None if unknown, or on the log scale without a positive ``value``."""
        if self.mdc95 is None:
            return None
        if self.scale is ErrorScale.ABSOLUTE:
            return self.mdc95
        if value is None or not value > 0:
            return None
        return value * -math.expm1(-self.mdc95)


NO_ERROR = DayToDayError(None, None, 0, 0, None, "none")


def pooled_error(
    values: Sequence[tuple[float, float, str]],
    source: str,
    min_pairs: int = MIN_PAIRS,
    scale: ErrorScale = ErrorScale.ABSOLUTE,
) -> DayToDayError:
    """The day-to-day error from ``(test, retest, subject)`` value pairs of one parameter (on ``scale``: for
    :attr:`ErrorScale.LOG` the values are already logarithms).

    SEM = SD of the retest differences / sqrt(2), the SD taken about zero (sqrt(mean d^2)): a test and its
    retest measure the same arm, so a systematic shift between them is measurement error too, and counting
    it keeps a few pairs that happen to agree from shrinking the MDC. MDC95 = t(0.975, n) x sqrt(2) x SEM
    (1.96 x sqrt(2) x SEM for many pairs). Fewer than ``min_pairs`` pairs give ``sem`` and ``mdc95`` None.
    """
    pairs = [(a, b, s) for a, b, s in values if math.isfinite(a) and math.isfinite(b)]
    n = len(pairs)
    subjects = len({s for _, _, s in pairs})
    if n < max(min_pairs, 2):
        return DayToDayError(None, None, n, subjects, None, source if n else "none", scale)
    x = np.array([[a, b] for a, b, _ in pairs])
    sd_diff = float(np.sqrt(np.mean((x[:, 1] - x[:, 0]) ** 2)))
    sem = sd_diff / math.sqrt(2.0)
    icc = icc_agreement(x) if subjects >= 2 else None
    return DayToDayError(sem, t95(n) * sd_diff, n, subjects, icc, source, scale)


def icc_agreement(x: npt.ArrayLike) -> float | None:
    """ICC(2,1), two-way random, absolute agreement, of an (n, k) table (rows: pairs, columns: test, retest)."""
    table = np.asarray(x, dtype=np.float64)
    n, k = table.shape
    if n < 2 or k < 2:
        return None
    grand = table.mean()
    ssr = k * float(np.sum((table.mean(axis=1) - grand) ** 2))
    ssc = n * float(np.sum((table.mean(axis=0) - grand) ** 2))
    sse = float(np.sum((table - grand) ** 2)) - ssr - ssc
    msr, msc, mse = ssr / (n - 1), ssc / (k - 1), sse / ((n - 1) * (k - 1))
    denominator = msr + (k - 1) * mse + k * (msc - mse) / n
    if not denominator > 0:
        return None
    return (msr - mse) / denominator


def retest_values(
    key: ParamKey, pairs: Iterable[RetestPair], scale: ErrorScale = ErrorScale.ABSOLUTE
) -> list[tuple[float, float, str]]:
    """``(test, retest, subject)`` of ``key`` in each pair that holds it on both sides, on ``scale`` (the natural
    logarithms for :attr:`ErrorScale.LOG`, where a pair with a value <= 0, at its bound, is left out)."""
    found = []
    for pair in pairs:
        a, b = pair.test.parameters.get(key), pair.retest.parameters.get(key)
        if a is None or b is None or a.value is None or b.value is None:
            continue
        if scale is ErrorScale.ABSOLUTE:
            found.append((a.value, b.value, pair.test.subject))
        elif a.value > 0 and b.value > 0:
            found.append((math.log(a.value), math.log(b.value), pair.test.subject))
    return found


def consistency_p(own: Sequence[tuple[float, float, str]], others: Sequence[tuple[float, float, str]]) -> float:
    """Two-sided p of the F-test that ``own`` and ``others`` retest differences have one variance (each taken about
    zero, as the SEM is: mean squared difference over its number of pairs); 0 with fewer than 2 pairs in either."""
    from scipy.stats import f

    if len(own) < 2 or len(others) < 2:
        return 0.0
    own_ms = float(np.mean([(b - a) ** 2 for a, b, _ in own]))
    others_ms = float(np.mean([(b - a) ** 2 for a, b, _ in others]))
    if not others_ms > 0 or not own_ms > 0:
        return 0.0
    ratio = own_ms / others_ms
    below = float(f.cdf(ratio, len(own), len(others)))
    return min(1.0, 2.0 * min(below, 1.0 - below))


def day_to_day_error(
    key: ParamKey, subject: str, cell: str, pairs: Sequence[RetestPair], min_pairs: int = MIN_PAIRS
) -> DayToDayError:
    """The error to judge ``subject``'s changes of ``key`` by, on :func:`scale_of` ``key``.

    With at least ``min_pairs`` of its own, the subject's pairs, pooled with every pair of its cell where the
    other subjects' differences have the same variance (two-sided F-test, p > :data:`POOL_ALPHA`): more pairs
    give a tighter limit where the subject measures like its peers, and a subject measured worse keeps its own
    error. With fewer own pairs, its cell's.
    """
    scale = scale_of(key)
    own_values = retest_values(key, (p for p in pairs if p.test.subject == subject), scale)
    cell_values = retest_values(key, (p for p in pairs if p.test.cell == cell), scale)
    own = pooled_error(own_values, "subject", min_pairs, scale)
    cell_error = pooled_error(cell_values, "cell", min_pairs, scale)
    if own.known:
        others = retest_values(key, (p for p in pairs if p.test.cell == cell and p.test.subject != subject), scale)
        return cell_error if consistency_p(own_values, others) > POOL_ALPHA else own
    if cell_error.known or cell_error.n_pairs >= own.n_pairs:
        return cell_error
    return own
