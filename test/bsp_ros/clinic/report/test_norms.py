"""Published healthy ranges of passive moments: where an estimate (value ± 2 SD) sits, by hand-computed cases, and the
report's rows and HTML for a simulated history."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from bsp_ros.clinic.histories import Patient, session_estimate
from bsp_ros.clinic.report import analyse, render_report
from bsp_ros.clinic.report.norm_rows import NORMS_TITLE, norm_rows
from bsp_ros.clinic.report.norms import (
    HEALTHY_RANGES,
    PLACEMENT_WORDS,
    HealthyRange,
    Placement,
    RangeKind,
    healthy_range,
    place,
)
from bsp_ros.clinic.store import SubjectRecord, open_store

ELBOW = healthy_range("elbow", "stiffness_nm_per_rad")


def test_the_elbow_stiffness_range_is_the_published_one() -> None:
    assert ELBOW is not None
    assert (ELBOW.low, ELBOW.high, ELBOW.unit) == (0.40, 1.8, "N·m/rad")
    assert ELBOW.kind is RangeKind.OBSERVED and ELBOW.n_subjects == 19
    assert "Wiegner" in ELBOW.citation and "1986" in ELBOW.reference
    # No range was found in a unit bsp_ros measures for friction, damping, or the shoulder and wrist.
    assert healthy_range("elbow", "coulomb_nm") is None and healthy_range("wrist", "stiffness_nm_per_rad") is None
    assert all(r.low < r.high and r.n_subjects > 0 for r in HEALTHY_RANGES)


@pytest.mark.parametrize(
    ("value", "std", "expected"),
    [
        (1.0, 0.1, Placement.WITHIN),  # 0.8 .. 1.2 inside 0.4 .. 1.8
        (1.5, 0.1, Placement.WITHIN),  # 1.3 .. 1.7
        (2.3, 0.2, Placement.ABOVE),  # 1.9 > 1.8
        (2.1, 0.2, Placement.NEAR_HIGH),  # 1.7 .. 2.5 reaches into the range
        (2.0, 0.05, Placement.ABOVE),  # 1.9 > 1.8
        (1.9, 0.2, Placement.NEAR_HIGH),  # the value above, but 1.5 .. 2.3 reaches into the range
        (0.1, 0.1, Placement.BELOW),  # 0.3 < 0.4
        (0.25, 0.1, Placement.NEAR_LOW),  # 0.05 .. 0.45 reaches into the range
        (0.5, 0.1, Placement.NEAR_LOW),  # 0.3 .. 0.7
        (1.1, 0.4, Placement.TOO_ROUGH),  # 0.3 .. 1.9 reaches past both ends
        (1.0, float("nan"), Placement.TOO_ROUGH),
        (1.0, None, Placement.TOO_ROUGH),
        (1.0, -0.1, Placement.TOO_ROUGH),
    ],
)
def test_placement_takes_two_sd_of_the_estimate_into_account(value: float, std: float | None, expected: str) -> None:
    assert place(value, std, ELBOW) is expected


def test_without_a_range_there_is_no_placement() -> None:
    assert place(1.0, 0.1, None) is Placement.NO_RANGE
    assert PLACEMENT_WORDS[Placement.NO_RANGE] == "no published range"
    assert set(PLACEMENT_WORDS) == set(Placement)


def test_a_mean_2sd_range_places_the_same_way() -> None:
    healthy = HealthyRange(
        joint="elbow",
        quantity="viscous_nms",
        unit="N·m·s/rad",
        low=0.1 - 2 * 0.02,
        high=0.1 + 2 * 0.02,
        kind=RangeKind.MEAN_2SD,
        population="test",
        n_subjects=10,
        conditions="",
        citation="",
        reference="",
        url="",
    )
    assert place(0.2, 0.01, healthy) is Placement.ABOVE  # 0.18 > 0.14
    assert place(0.1, 0.01, healthy) is Placement.WITHIN  # 0.08 .. 0.12 inside 0.06 .. 0.14


SUBJECT = "N1"


@pytest.fixture(scope="module")
def stiff_arm(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two weekly visits of an arm whose simulated elbow stiffness (2.6 N·m/rad) is above the published range."""
    patient = Patient("male", 80.0, 1.80, (0.5, 0.4, 0.06), (0.0, 2.6, 0.0), passive="coulomb+offset+stiffness")
    path = tmp_path_factory.mktemp("norms") / "clinic.sqlite"
    with open_store(path) as store:
        store.set_subject(SubjectRecord(SUBJECT, 80.0, 1.80, "male", "left", "left"))
        for week in range(2):
            store.add_estimate(session_estimate(patient, 7 * week, 4100 + week), SUBJECT)
    return path


def test_the_report_places_the_elbow_stiffness_and_names_the_source(stiff_arm: Path) -> None:
    with open_store(stiff_arm) as store:
        analysis = analyse(SUBJECT, store.sessions(SUBJECT), subject_record=store.subject_record(SUBJECT))
    rows, without = norm_rows(analysis)
    assert [r.healthy for r in rows] == [ELBOW]
    row = rows[0]
    # The estimate recovers the simulated 2.6 N·m/rad well enough to sit clearly above 1.8.
    assert math.isfinite(row.std) and row.std > 0 and abs(row.value - 2.6) < 3 * row.std
    assert row.value - 2 * row.std > 1.8 and row.placement is Placement.ABOVE
    assert "elbow friction" in without and "shoulder friction" in without
    page = render_report(analysis)
    detail = page.split("<section id='detail'>")[1]
    table = detail.split("id='norms'")[1].split("</table>")[0]
    assert NORMS_TITLE in detail and "above the healthy range" in table and "Wiegner and Watts (1986)" in table
    assert "0.40 to 1.8 N·m/rad" in table
    assert "No published healthy range was found for: " in detail and "elbow friction" in detail
    assert detail.index("id='peers'") < detail.index("id='norms'")
