"""A positive passive parameter's day-to-day error is relative: judged on the log scale, pooled with the cell's
retest pairs where the subject's own agree with them (F-test), and its limits given back in the parameter's unit."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from bsp_ros.clinic.mdc import (
    DAY_NS,
    ErrorScale,
    RetestPair,
    consistency_p,
    day_to_day_error,
    retest_values,
)
from bsp_ros.clinic.report.analysis import Change, Point
from bsp_ros.clinic.store.records import ParamKey, Quality, Quantity, SessionRecord
from bsp_ros.core.estimate_schema import Source

FRICTION: ParamKey = ("joints", "elbow", "coulomb_nm")
OFFSET: ParamKey = ("joints", "elbow", "offset_nm")


def _record(subject: str, day: int, value: float, *, retest: bool) -> SessionRecord:
    return SessionRecord(
        subject=subject,
        session_time_ns=day * DAY_NS + (3_600 * 10**9 if retest else 0),
        source=f"{subject}_{day}_{int(retest)}.mcap",
        method=None,
        config={},
        subject_info={},
        estimate_schema="bsp_ros/estimate/1",
        quality=Quality(valid=True),
        parameters={
            FRICTION: Quantity(value=value, std=0.01, source=Source.DATA),
            OFFSET: Quantity(value=value - 0.5, std=0.01, source=Source.DATA),
        },
        retest=retest,
    )


def _pairs(subject: str, level_nm: float, relative_sd: float, count: int, rng: np.random.Generator) -> list[RetestPair]:
    """``count`` retest pairs of an arm of friction ``level_nm`` measured with a relative error ``relative_sd``."""
    out = []
    for day in range(count):
        test, retest = level_nm * np.exp(relative_sd * rng.standard_normal(2))
        out.append(
            RetestPair(
                _record(subject, day, float(test), retest=False), _record(subject, day, float(retest), retest=True)
            )
        )
    return out


def test_an_error_that_grows_with_the_value_is_one_relative_error() -> None:
    """Subjects of frictions 0.2 to 1.0 N m, each measured within 6 % (log sd): their log-ratios share one SD
    (0.06 sqrt 2), where their differences in N m grow fivefold."""
    rng = np.random.default_rng(53)
    pairs = [p for k, level in enumerate((0.2, 0.4, 0.6, 0.8, 1.0)) for p in _pairs(f"S{k}", level, 0.06, 40, rng)]
    error = day_to_day_error(FRICTION, "S4", "", pairs)
    assert error.scale is ErrorScale.LOG and error.sem == pytest.approx(0.06, rel=0.1)
    # The subjects agree on the log scale: all 200 pairs judge each.
    assert (error.source, error.n_pairs) == ("cell", 200)
    low = retest_values(FRICTION, pairs[:40])
    high = retest_values(FRICTION, pairs[-40:])
    # In N m the high-friction arm's differences are five times the low one's: not one error (F-test rejects).
    assert consistency_p(high, low) < 1e-6
    # A quantity that can be 0 or negative keeps the absolute scale.
    assert day_to_day_error(OFFSET, "S4", "", pairs).scale is ErrorScale.ABSOLUTE


def test_a_subject_measured_worse_than_its_cell_keeps_its_own_error() -> None:
    rng = np.random.default_rng(54)
    peers = [p for k in range(4) for p in _pairs(f"P{k}", 0.5, 0.05, 6, rng)]
    alike = _pairs("A", 0.8, 0.05, 6, rng)
    worse = _pairs("W", 0.8, 0.20, 6, rng)
    pooled = day_to_day_error(FRICTION, "A", "", [*peers, *alike, *worse[:0]])
    own = day_to_day_error(FRICTION, "W", "", [*peers, *worse])
    assert (pooled.source, pooled.n_pairs) == ("cell", 30)
    assert (own.source, own.n_pairs) == ("subject", 6)
    assert own.sem is not None and pooled.sem is not None and own.sem > 2 * pooled.sem


def test_a_relative_change_is_judged_on_the_log_scale_and_its_limits_read_in_units() -> None:
    rng = np.random.default_rng(55)
    error = day_to_day_error(FRICTION, "A", "", _pairs("A", 0.8, 0.06, 30, rng))
    assert error.mdc95 is not None and error.sem is not None

    def change(before: float, after: float) -> Change:
        points = [
            Point(
                number=k + 1, session_id=k + 1, time_ns=k * 7 * DAY_NS, value=v, std=0.01 * v, source="data", valid=True
            )
            for k, v in enumerate((before, after))
        ]
        return Change(FRICTION, points[0], points[1], after - before, error, comparisons=20)

    fall, rise = change(0.8, 0.5), change(0.5, 0.8)
    # One ratio, judged alike either way.
    assert fall.scaled_delta == pytest.approx(-(rise.scaled_delta or 0.0)) == pytest.approx(math.log(0.625))
    assert fall.flagged == rise.flagged and fall.beyond_mdc == rise.beyond_mdc
    # The limits in N m, from the earlier value in the change's direction.
    mdc = max(error.mdc95, 1.96 * math.hypot(0.01, 0.01))
    assert fall.mdc95 == pytest.approx(0.8 * (1.0 - math.exp(-mdc)))
    assert rise.mdc95 == pytest.approx(0.5 * (math.exp(mdc) - 1.0))
    assert fall.mdc_percent == pytest.approx(100.0 * (1.0 - math.exp(-mdc)))
    for c in (fall, rise, change(0.8, 0.78), change(0.8, 0.7)):
        assert c.limit is not None and c.mdc95 is not None and c.limit > c.mdc95
        assert c.possible == (abs(c.delta) > c.limit) and c.beyond_mdc == (abs(c.delta) > c.mdc95)
    assert fall.possible and not change(0.8, 0.78).possible
    # A possible change is flagged once the next session, against the same earlier one, is beyond it the same way.
    assert fall.awaiting and not fall.flagged
    assert replace(fall, confirmed_by=change(0.8, 0.52)).flagged
    assert not replace(fall, confirmed_by=change(0.8, 0.78)).flagged  # back within the error
    assert not replace(fall, confirmed_by=change(0.8, 1.3)).flagged  # beyond, but the other way
