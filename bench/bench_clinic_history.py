"""A clinic's history in a store: three simulated patients over ten weeks with same-day retests, then reports.

Patient P-FRIC: elbow friction falls 0.80 -> 0.38 Nm in steps, one session not usable (no elbow motion).
Patient P-SAME: nothing changes; markers re-placed and the sensor re-zeroed every session.
Patient P-STIF: elbow stiffness falls 1.5 -> 1.0 Nm/rad.
Each has retests on the first five days. Prints every flagged step and writes the reports.

With ``--false-flags N``: N unchanged arms instead (people of seeded sex, size and passive moments, six weekly
visits each with a same-day retest, markers re-placed and the sensor re-zeroed every session), and how many of their
reports show any flag by the report's rule (a step the next session confirms, at a level set for the report's
confirmable steps) and with each comparison at 95 % alone (its MDC95), and how many of their sessions were
invalid (by the first invalid finding's code).

Every session re-places every marker, shoulder to contact point, by a Gaussian draw of ``--placement-sd-mm`` per
in-plane axis (default: the 2 mm `bsp identify` assumes); ``--placement-sd-mm 0`` re-places the shoulder and elbow
markers alone, within +-3 mm.

    python bench/bench_clinic_history.py OUT_DIR [--placement-sd-mm MM] [--duration-s S]
    python bench/bench_clinic_history.py OUT_DIR --false-flags 60 [--first-seed 0] [--placement-sd-mm MM]
        [--duration-s S]
"""

from __future__ import annotations

import argparse
import collections
import random
import time
from dataclasses import replace
from pathlib import Path

from bsp_ros.clinic.histories import PLACEMENT_SD_MM, Patient, session_estimate
from bsp_ros.clinic.report import analyse, write_csv, write_html, write_pdf
from bsp_ros.clinic.store import SubjectRecord, open_store

MODEL = "coulomb+offset+stiffness"
PLANS = {
    "P-FRIC": [(0.80, 1.5)] * 2 + [(0.66, 1.5)] * 3 + [(0.52, 1.5)] * 3 + [(0.38, 1.5)] * 2,
    "P-SAME": [(0.28, 1.5)] * 10,
    "P-STIF": [(0.28, 1.5)] * 5 + [(0.28, 1.0)] * 5,
}


def _placement(placement_sd_mm: float) -> str:
    """How the sessions re-place the markers, in words."""
    if placement_sd_mm > 0.0:
        return f"every marker re-placed at {placement_sd_mm:g} mm sd"
    return "shoulder and elbow markers re-placed within +-3 mm"


def main(out: Path, placement_sd_mm: float, duration_s: float) -> None:
    out.mkdir(parents=True, exist_ok=True)
    store_path = out / "clinic.sqlite"
    store_path.unlink(missing_ok=True)
    started = time.perf_counter()
    with open_store(store_path) as store:
        for k, (subject, plan) in enumerate(PLANS.items()):
            store.set_subject(SubjectRecord(subject, 68.0, 1.65, "female", "left", "left"))
            for week, (coulomb, stiffness) in enumerate(plan):
                patient = Patient(
                    passive=MODEL, coulomb_nm=(0.5, coulomb, 0.06), stiffness_nm_per_rad=(0.0, stiffness, 0.0)
                )
                seed = 1000 * k + week
                if subject == "P-FRIC" and week == 6:
                    patient = replace(patient)  # same arm; the session below is cut too short to be usable
                    document = session_estimate(
                        patient, 7 * week, seed, duration_s=8.0, placement_sd_mm=placement_sd_mm
                    )
                else:
                    document = session_estimate(
                        patient, 7 * week, seed, placement_sd_mm=placement_sd_mm, duration_s=duration_s
                    )
                store.add_estimate(document, subject)
                if week < 5:
                    retest = session_estimate(
                        patient,
                        7 * week,
                        seed + 500,
                        retest=True,
                        placement_sd_mm=placement_sd_mm,
                        duration_s=duration_s,
                    )
                    store.add_estimate(retest, subject)
        print(f"simulated and stored in {time.perf_counter() - started:.1f} s ({_placement(placement_sd_mm)})")
        for subject in PLANS:
            analysis = analyse(
                subject, store.sessions(subject), pool=store.sessions(), subject_record=store.subject_record(subject)
            )
            for series in analysis.series:
                for change in series.changes:
                    print(
                        f"{subject} {series.label}: {change.before.value:.3f} -> {change.after.value:.3f} "
                        f"(MDC95 {change.mdc95:.3f}, {series.error.n_pairs} pairs, {series.error.source})"
                    )
            write_html(analysis, out / f"{subject}.html")
            write_pdf(analysis, out / f"{subject}.pdf")
            write_csv(analysis, out / f"{subject}.csv")
    print(f"reports in {out}")


UNCHANGED_VISITS = 6


def unchanged_patient(rng: random.Random) -> Patient:
    """A person of seeded sex, size and passive moments (the ranges of docs/clinic.md's simulated histories)."""
    sex = rng.choice(("female", "male"))
    height = rng.uniform(1.55, 1.75) if sex == "female" else rng.uniform(1.65, 1.90)
    return Patient(
        sex=sex,
        body_mass_kg=rng.uniform(50.0, 95.0),
        height_m=height,
        coulomb_nm=(rng.uniform(0.3, 0.7), rng.uniform(0.15, 0.8), rng.uniform(0.04, 0.09)),
        stiffness_nm_per_rad=(0.0, rng.uniform(0.8, 2.0), 0.0),
        passive=MODEL,
    )


def false_flags(out: Path, count: int, first_seed: int, placement_sd_mm: float, duration_s: float) -> None:
    """Simulate ``count`` unchanged arms and print how many reports flag anything, with and without the report's
    limit, the largest change over its limit, and how many sessions were invalid and why."""
    out.mkdir(parents=True, exist_ok=True)
    store_path = out / "unchanged.sqlite"
    store_path.unlink(missing_ok=True)
    started = time.perf_counter()
    any_limit = any_single = comparisons = sessions = 0
    worst = 0.0
    invalid: collections.Counter[str] = collections.Counter()
    with open_store(store_path) as store:
        for k in range(count):
            seed = first_seed + k
            rng = random.Random(seed)
            patient, subject = unchanged_patient(rng), f"U{seed:04d}"
            record = SubjectRecord(
                subject=subject,
                body_mass_kg=patient.body_mass_kg,
                height_m=patient.height_m,
                sex=patient.sex,
                arm="left",
            )
            store.set_subject(record)
            for week in range(UNCHANGED_VISITS):
                base = 100_000 + 100 * seed + 2 * week
                for retest in (False, True):
                    document = session_estimate(
                        patient,
                        7 * week,
                        base + retest,
                        retest=retest,
                        placement_sd_mm=placement_sd_mm,
                        duration_s=duration_s,
                    )
                    store.add_estimate(document, subject)
            records = store.sessions(subject)
            for stored in records:
                verdict = stored.quality.verdict()
                invalid.update([] if stored.quality.valid else [verdict.code if verdict else "unknown"])
            sessions += len(records)
            analysis = analyse(subject, records, subject_record=store.subject_record(subject))
            judged = [c for s in analysis.series for c in s.comparisons]
            flagged, beyond = sum(c.flagged for c in judged), sum(c.beyond_mdc for c in judged)
            ratios = [abs(c.delta) / c.limit for c in judged if c.judged and c.limit]
            worst = max([worst, *ratios])
            any_limit += flagged > 0
            any_single += beyond > 0
            comparisons += len(judged)
            print(
                f"{subject}: {len(judged)} comparisons, {flagged} flagged, {beyond} beyond one comparison's MDC95, "
                f"largest change {max(ratios, default=0.0):.2f} of its limit, "
                f"{sum(not r.quality.valid for r in records)} of {len(records)} sessions invalid"
            )
    causes = ", ".join(f"{code} {n}" for code, n in invalid.most_common()) or "none"
    print(
        f"{count} unchanged arms ({comparisons / max(count, 1):.1f} comparisons a report, "
        f"{_placement(placement_sd_mm)}, {duration_s:g} s sessions) in {time.perf_counter() - started:.0f} s: any "
        f"flag by the report's rule in {any_limit} reports, with each comparison at 95 % alone (its MDC95) in "
        f"{any_single}; largest change {worst:.2f} of its limit; {sum(invalid.values())} of {sessions} sessions "
        f"invalid ({causes})"
    )


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", default="clinic_history", type=Path)
    parser.add_argument("--false-flags", type=int, default=0, metavar="N", help="count false flags over N arms")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument(
        "--placement-sd-mm",
        type=float,
        default=PLACEMENT_SD_MM,
        metavar="MM",
        help="re-place every marker by this sd per axis each session (0: shoulder and elbow alone, +-3 mm) "
        f"(default: {PLACEMENT_SD_MM:g}, what bsp identify assumes)",
    )
    parser.add_argument(
        "--duration-s",
        type=float,
        default=40.0,
        metavar="S",
        help="each session's length (default: 40, the report tests' histories)",
    )
    args = parser.parse_args()
    if args.false_flags > 0:
        false_flags(args.out, args.false_flags, args.first_seed, args.placement_sd_mm, args.duration_s)
    else:
        main(args.out, args.placement_sd_mm, args.duration_s)
