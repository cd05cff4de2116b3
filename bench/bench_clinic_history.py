"""A clinic's history in a store: three simulated patients over ten weeks with same-day retests, then reports.

Patient P-FRIC: elbow friction falls 0.80 -> 0.38 Nm in steps, one session not usable (no elbow motion).
Patient P-SAME: nothing changes; markers re-placed (+-3 mm) and the sensor re-zeroed every session.
Patient P-STIF: elbow stiffness falls 1.5 -> 1.0 Nm/rad.
Each has retests on the first five days. Prints every flagged step and writes the reports.

    python bench/bench_clinic_history.py OUT_DIR
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

from bsp_ros.clinic.histories import Patient, session_estimate
from bsp_ros.clinic.report import analyse, write_csv, write_html, write_pdf
from bsp_ros.clinic.store import SubjectRecord, open_store

MODEL = "coulomb+offset+stiffness"
PLANS = {
    "P-FRIC": [(0.80, 1.5)] * 2 + [(0.66, 1.5)] * 3 + [(0.52, 1.5)] * 3 + [(0.38, 1.5)] * 2,
    "P-SAME": [(0.28, 1.5)] * 10,
    "P-STIF": [(0.28, 1.5)] * 5 + [(0.28, 1.0)] * 5,
}


def main(out: Path) -> None:
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
                    document = session_estimate(patient, 7 * week, seed, duration_s=8.0)
                else:
                    document = session_estimate(patient, 7 * week, seed)
                store.add_estimate(document, subject)
                if week < 5:
                    store.add_estimate(session_estimate(patient, 7 * week, seed + 500, retest=True), subject)
        print(f"simulated and stored in {time.perf_counter() - started:.1f} s")
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


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "clinic_history"))
