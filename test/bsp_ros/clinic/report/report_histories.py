"""Simulated histories for the report's judgement: six weekly visits, each with a same-day retest (markers re-placed,
sensor re-zeroed), written to a SQLite store in seconds.

- ``U2``..``U5``: unchanged arms of different people.
- ``D1``: elbow friction falls in two ~25 % steps, at visits 3 and 5 (0.80 -> 0.60 -> 0.45 N m).
- ``R1`` (its own store): the retests were recorded with a friction-only passive model but one, so the stiffness
  has a single retest pair.
- ``T1`` (its own store): a 0.3 kg handle; every session tared but the latest visit, which was not.

The shoulder and elbow markers are re-placed within +-3 mm every session, the wrist and hand markers sit exactly;
``build_peers(..., placement_sd_mm=2.0)`` re-places every marker by a Gaussian draw of 2 mm per axis instead (the sd
`bsp identify` assumes), the day-to-day error of a clinic where every marker goes on anew: one of U4's twelve 40 s
sessions is then invalid, and each of D1's friction steps is a possible change in the report of its visit and
flagged in the next.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from bsp_ros.clinic.histories import Patient, session_estimate
from bsp_ros.clinic.store import SubjectRecord, open_store

MODEL = "coulomb+offset+stiffness"
VISITS = 6
UNCHANGED = {
    "U2": Patient("female", 60.0, 1.60, (0.5, 0.28, 0.06), (0.0, 1.5, 0.0), passive=MODEL),
    "U3": Patient("male", 82.0, 1.80, (0.6, 0.35, 0.08), (0.0, 1.0, 0.0), passive=MODEL),
    "U4": Patient("male", 75.0, 1.75, (0.4, 0.2, 0.05), (0.0, 2.0, 0.0), passive=MODEL),
    "U5": Patient("female", 70.0, 1.68, (0.5, 0.5, 0.06), (0.0, 1.2, 0.0), passive=MODEL),
}
DECLINE = "D1"
DECLINE_FRICTION = (0.80, 0.80, 0.60, 0.60, 0.45, 0.45)
DECLINE_PATIENT = Patient("female", 68.0, 1.65, (0.5, 0.8, 0.06), (0.0, 1.5, 0.0), passive=MODEL)
FEW_PAIRS = "R1"
UNTARED = "T1"
HANDLE_KG = 0.3


def _record(patient: Patient, subject: str) -> SubjectRecord:
    return SubjectRecord(subject, patient.body_mass_kg, patient.height_m, patient.sex, "left", "left")


def build_peers(path: Path, placement_sd_mm: float = 0.0) -> Path:
    """The unchanged arms and the two-step decline in one store (one cell); ``placement_sd_mm`` > 0 re-places every
    marker by that sd every session (:func:`~bsp_ros.clinic.histories.session_estimate`)."""
    plans = {s: (p, [p.coulomb_nm[1]] * VISITS) for s, p in UNCHANGED.items()}
    plans[DECLINE] = (DECLINE_PATIENT, list(DECLINE_FRICTION))
    with open_store(path) as store:
        for k, (subject, (patient, plan)) in enumerate(plans.items()):
            store.set_subject(_record(patient, subject))
            for week, friction in enumerate(plan):
                arm = replace(patient, coulomb_nm=(patient.coulomb_nm[0], friction, patient.coulomb_nm[2]))
                seed = 1000 + 100 * k + week
                day = 7 * week
                store.add_estimate(session_estimate(arm, day, seed, placement_sd_mm=placement_sd_mm), subject)
                retest = session_estimate(arm, day, seed + 50, retest=True, placement_sd_mm=placement_sd_mm)
                store.add_estimate(retest, subject)
    return path


def build_few_pairs(path: Path) -> Path:
    """``R1``: every visit with stiffness in its passive model; only the first retest too, the others without it
    (their estimates hold no stiffness, as a retest identified with another passive model)."""
    patient = UNCHANGED["U2"]
    with open_store(path) as store:
        store.set_subject(_record(patient, FEW_PAIRS))
        for week in range(VISITS):
            store.add_estimate(session_estimate(patient, 7 * week, 3000 + week), FEW_PAIRS)
            retest = session_estimate(patient, 7 * week, 3050 + week, retest=True)
            if week > 0:
                for joint in retest["joints"].values():
                    joint.pop("stiffness_nm_per_rad", None)
            store.add_estimate(retest, FEW_PAIRS)
    return path


def build_untared(path: Path) -> Path:
    """``T1``: a 0.3 kg handle, every session tared but the latest visit."""
    patient = UNCHANGED["U2"]
    with open_store(path) as store:
        store.set_subject(_record(patient, UNTARED))
        for week in range(VISITS):
            tared = week < VISITS - 1
            document = session_estimate(patient, 7 * week, 4000 + week, handle_mass_kg=HANDLE_KG, tared=tared)
            store.add_estimate(document, UNTARED)
            retest = session_estimate(patient, 7 * week, 4050 + week, handle_mass_kg=HANDLE_KG, tared=True, retest=True)
            store.add_estimate(retest, UNTARED)
    return path


LATEST_WITHOUT = "L1"


def build_latest_without(path: Path, quantity: str = "stiffness_nm_per_rad") -> Path:
    """``L1``: U2's unchanged arm, the latest visit identified without ``quantity`` (another passive model); its
    retests and every earlier visit hold it."""
    patient = UNCHANGED["U2"]
    with open_store(path) as store:
        store.set_subject(_record(patient, LATEST_WITHOUT))
        for week in range(VISITS):
            document = session_estimate(patient, 7 * week, 1000 + week)
            if week == VISITS - 1:
                for joint in document["joints"].values():
                    joint.pop(quantity, None)
            store.add_estimate(document, LATEST_WITHOUT)
            store.add_estimate(session_estimate(patient, 7 * week, 1050 + week, retest=True), LATEST_WITHOUT)
    return path


CURVES = "C2"
CURVE_ANGLES_DEG = tuple(20.0 + 1.0 * k for k in range(25))


def _with_curves(document: dict, shift_nm: float) -> dict:
    """``document`` with a passive-moment curve per joint: a linear spring through 0.1 N m at 30°, shifted by
    ``shift_nm`` (a session's day-to-day error)."""
    for k, joint in enumerate(("shoulder", "elbow", "wrist")):
        stiffness = (0.5, 1.5, 0.3)[k]
        moment = [stiffness * (a - 30.0) * 3.141592653589793 / 180.0 + 0.1 + shift_nm for a in CURVE_ANGLES_DEG]
        curve = {"angle_deg": list(CURVE_ANGLES_DEG), "moment_nm": moment, "std_nm": [0.01] * len(moment)}
        document["joints"].setdefault(joint, {})["passive_curve"] = curve
    return document


def build_curves(path: Path, visits: int = 3) -> Path:
    """``C2``: U2's unchanged arm over ``visits`` weekly visits (no retests) with a passive-moment curve per joint."""
    import random

    patient = UNCHANGED["U2"]
    rng = random.Random(5)
    with open_store(path) as store:
        store.set_subject(_record(patient, CURVES))
        for week in range(visits):
            document = session_estimate(patient, 7 * week, 5000 + week)
            store.add_estimate(_with_curves(document, rng.gauss(0.0, 0.01)), CURVES)
    return path
