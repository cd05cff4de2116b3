"""Minimal detectable change from test-retest pairs: same subject, same day, the arm re-attached in between."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from bsp_ros.clinic.store.records import ParamKey, SessionRecord

Z95 = 1.96
"""The two-sided 95 % normal quantile of MDC95 = 1.96 x sqrt(2) x SEM."""
MIN_PAIRS = 5
"""Fewer retest pairs give no MDC: the SD of fewer differences is too uncertain to judge changes by."""
DAY_NS = 86_400 * 10**9

RETEST_METHOD = (
    "The minimal detectable change (MDC95) comes from test-retest pairs: the same subject measured twice on "
    "the same day, the arm taken out and re-attached (markers re-placed, strap re-fastened, sensor re-zeroed) in "
    "between. SEM = SD of the retest differences / √2 (the SD taken about zero, so a systematic shift between "
    "test and retest counts as error too); MDC95 = 1.96 × √2 × SEM, where 1.96 is replaced by Student's t "
    "quantile for n degrees of freedom while there are few pairs (n pairs), so a small sample "
    "does not claim changes its own uncertainty could explain. A subject's own pairs are used once there are "
    f"at least {MIN_PAIRS}; until then the pairs of every subject measured in the same cell. The spread of "
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
    """

    sem: float | None
    mdc95: float | None
    n_pairs: int
    n_subjects: int
    icc: float | None
    source: str

    @property
    def known(self) -> bool:
        """Whether changes can be judged against this error."""
        return self.mdc95 is not None


NO_ERROR = DayToDayError(None, None, 0, 0, None, "none")


def pooled_error(values: Sequence[tuple[float, float, str]], source: str, min_pairs: int = MIN_PAIRS) -> DayToDayError:
    """The day-to-day error from ``(test, retest, subject)`` value pairs of one parameter.

    SEM = SD of the retest differences / sqrt(2), the SD taken about zero (sqrt(mean d^2)): a test and its
    retest measure the same arm, so a systematic shift between them is measurement error too, and counting
    it keeps a few pairs that happen to agree from shrinking the MDC. MDC95 = t(0.975, n) x sqrt(2) x SEM
    (1.96 x sqrt(2) x SEM for many pairs). Fewer than ``min_pairs`` pairs give ``sem`` and ``mdc95`` None.
    """
    pairs = [(a, b, s) for a, b, s in values if math.isfinite(a) and math.isfinite(b)]
    n = len(pairs)
    subjects = len({s for _, _, s in pairs})
    if n < max(min_pairs, 2):
        return DayToDayError(None, None, n, subjects, None, source if n else "none")
    x = np.array([[a, b] for a, b, _ in pairs])
    sd_diff = float(np.sqrt(np.mean((x[:, 1] - x[:, 0]) ** 2)))
    sem = sd_diff / math.sqrt(2.0)
    return DayToDayError(sem, t95(n) * sd_diff, n, subjects, icc_agreement(x) if subjects >= 2 else None, source)


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


def day_to_day_error(
    key: ParamKey, subject: str, cell: str, pairs: Sequence[RetestPair], min_pairs: int = MIN_PAIRS
) -> DayToDayError:
    """The error to judge ``subject``'s changes of ``key`` by: its own pairs if enough, else its cell's."""

    def values(chosen: Iterable[RetestPair]) -> list[tuple[float, float, str]]:
        found = []
        for pair in chosen:
            a, b = pair.test.parameters.get(key), pair.retest.parameters.get(key)
            if a is not None and b is not None and a.value is not None and b.value is not None:
                found.append((a.value, b.value, pair.test.subject))
        return found

    own = pooled_error(values(p for p in pairs if p.test.subject == subject), "subject", min_pairs)
    if own.known:
        return own
    cell_error = pooled_error(values(p for p in pairs if p.test.cell == cell), "cell", min_pairs)
    if cell_error.known or cell_error.n_pairs >= own.n_pairs:
        return cell_error
    return own
