"""A clinic's simulated history in a SQLite store (in-process, about 30 sessions): what is planted, and the builder."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from bsp_ros.clinic.histories import Patient, session_estimate
from bsp_ros.clinic.store import SubjectRecord, open_store

MODEL = "coulomb+offset+stiffness"
WEEK_DAYS = 7
UNCHANGED = "U1"
FRICTION = "F1"
STIFFNESS = "S1"
# Per visit (one a week): (elbow friction Nm, elbow stiffness Nm/rad). Steps are planted at weeks 2 and 4.
PLANS = {
    UNCHANGED: [(0.28, 1.5)] * 10,
    FRICTION: [(0.80, 1.5)] * 2 + [(0.60, 1.5)] * 2 + [(0.40, 1.5)] * 2,
    # The 1.5 -> 1.0 Nm/rad fall, then a rise to 2.0 (spasticity returning): the day-to-day error of the
    # elbow stiffness with markers re-placed over the paper's small ranges is an MDC95 of about 0.43 Nm/rad, so the
    # fall is just beyond it and the rise twice it (testing "flagged exactly where beyond" needs a step clear of
    # the MDC; a fall to near 0 would end at the stiffness's bound, where a change is not judged).
    STIFFNESS: [(0.28, 1.5)] * 2 + [(0.28, 1.0)] * 2 + [(0.28, 2.0)] * 2,
}
RETEST_WEEKS = {UNCHANGED: 6, FRICTION: 6}  # retests on the first 6 visit days; S1 uses the cell's pairs
INVALID_DAY = {FRICTION: 3 * WEEK_DAYS + 3}  # a session too short to use, between two visits
INVALID_VALUE_NM = 5.0  # what the invalid session's estimate claims for the elbow friction


@dataclass(frozen=True)
class History:
    """The store and what was planted in it."""

    store: Path
    plans: dict[str, list[tuple[float, float]]]


def patient(coulomb: float, stiffness: float) -> Patient:
    """The simulated arm of one visit."""
    return Patient(passive=MODEL, coulomb_nm=(0.5, coulomb, 0.06), stiffness_nm_per_rad=(0.0, stiffness, 0.0))


def build_history(path: Path) -> History:
    """Three patients in one cell: unchanged (10 visits, 6 retests), friction falling (6 retests), stiffness falling."""
    with open_store(path) as store:
        for k, (subject, plan) in enumerate(PLANS.items()):
            store.set_subject(SubjectRecord(subject, 68.0, 1.65, "female", "left", "left"))
            for week, (coulomb, stiffness) in enumerate(plan):
                arm = patient(coulomb, stiffness)
                seed = 100 * k + week
                store.add_estimate(session_estimate(arm, WEEK_DAYS * week, seed), subject)
                if week < RETEST_WEEKS.get(subject, 0):
                    store.add_estimate(session_estimate(arm, WEEK_DAYS * week, seed + 50, retest=True), subject)
            if subject in INVALID_DAY:
                broken = session_estimate(patient(*plan[0]), INVALID_DAY[subject], 100 * k + 99, duration_s=8.0)
                assert not broken["quality"]["valid"]
                broken["joints"]["elbow"]["coulomb_nm"]["value"] = INVALID_VALUE_NM
                store.add_estimate(broken, subject)
    return History(path, PLANS)
