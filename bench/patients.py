"""Patients: `bsp identify` on MuJoCo arms that are not relaxed, and whether it says so and names the cause.

Usage: ``python bench/patients.py [--quick] [--seeds N] [--only CASE] [--passive auto] [--json OUT]
[--write-bags DIR]`` (with the worktree first on PYTHONPATH; ``bench/README.md``, "Patients").

Each case is a MuJoCo cell session (``test/physics/mujoco_cell.py``) with a patient (``mujoco_patient.py``):
relaxed controls at the paper's protocol (shoulder peak 0.03 rad/s), on a ``bsp plan`` trajectory and four times
faster; involuntary activity at 2/5/10/20 % of each joint's gravity torque; elbow spasticity at the paper's speed
and four times faster; a typical stroke arm (springs, 2 % activity, spasticity, sliding skin); sliding skin
markers; a tremor in the joints or shaking the handle; a slipping hand; a compliant strap; a two-speed session
(the paper's sines, the second half four times faster) of the elbow spasticity and of a control, whose
speed-dependent part (``speed_dependence``) is scored against the reflex torque imposed in the fast half. A seed
draws the arm (de Leva prior, friction, springs where the case has them), the noise and the patient's signals.
Truth is the arm's segment parameters and its RELAXED passive moments; what the patient did is truth.json's
``patient`` key.

Per case: runs, valid-and-right, VALID-AND-WRONG (some |z| > 3 on a data-sourced parameter), invalid-and-right,
invalid-and-wrong; two-sided calibration over the valid runs' data-sourced parameters (``calibration.py``: z RMS,
share within 1 and 2 std); the cause-naming rate: of the runs with a cause that are invalid or flagged (a finding of
severity ``weak``, or any finding beyond the routine notes of :data:`ROUTINE`), the share whose
``quality.findings[].code`` include a code of :data:`CAUSES` for the case; ``false n/m``: of the runs without a
cause (the controls, and a reflex that never fired: truth.json's ``patient.spasticity.active_fraction`` 0), those
whose codes name some patient cause (:data:`PATIENT_CODES`); the codes seen most often beyond the routine ones.

``--quick``: 2 seeds of 60 s, wrench at 250 Hz. ``--write-bags DIR``: one bag per case (the first seed) with its
truth.json into ``DIR/<case>/``, nothing identified.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import json
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import calibration
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "test" / "physics"))

from in_process import identify, planned_in_ranges
from mujoco_bag import write_bag
from mujoco_cell import CellOptions, draw_arm, paper_sine
from mujoco_emg import EmgRecording
from mujoco_patient import (
    ELBOW,
    CompliantStrap,
    HandSlip,
    Imposed,
    InvoluntaryActivity,
    Patient,
    SkinSliding,
    Spasticity,
    Tremor,
    TremorSite,
    patient_session,
    typical_stroke_arm,
)
from scoring import Counts

from bsp_ros.core.planning import planned_trajectory_from_file
from bsp_ros.core.planning.two_speed import TwoSpeedPath

# Case -> the finding codes that name its true cause. Patient-cause codes may not exist in the estimator yet.
CAUSES: dict[str, frozenset[str]] = {
    "control_paper": frozenset(),
    "control_plan": frozenset(),
    "control_fast": frozenset(),
    "activity_2": frozenset({"arm_active", "too_little_relaxed"}),
    "activity_5": frozenset({"arm_active", "too_little_relaxed"}),
    "activity_10": frozenset({"arm_active", "too_little_relaxed"}),
    "activity_20": frozenset({"arm_active", "too_little_relaxed"}),
    "activity_emg": frozenset({"arm_active", "too_little_relaxed"}),
    "spasticity_slow": frozenset({"spasticity", "friction_speed_dependent"}),
    "spasticity_fast": frozenset({"spasticity", "friction_speed_dependent"}),
    "stroke_arm": frozenset(
        {"arm_active", "too_little_relaxed", "spasticity", "friction_speed_dependent"}
        | {"skin_sliding", "placement_wider"}
    ),
    "skin_sliding": frozenset({"skin_sliding", "placement_wider"}),
    "tremor_joints": frozenset({"tremor", "tremor_friction"}),
    "tremor_handle": frozenset({"handle_shaken", "tremor"}),
    "hand_slip": frozenset({"hand_slipped"}),
    "compliant_strap": frozenset({"grip_compliant"}),
    "control_two_speed": frozenset(),
    "spasticity_two_speed": frozenset({"spasticity"}),
}
# Every code that names a patient cause (a control naming one is a false alarm).
PATIENT_CODES = frozenset(
    {"arm_active", "too_little_relaxed", "spasticity", "tremor", "tremor_friction", "handle_shaken", "hand_slipped"}
    | {"grip_compliant", "skin_sliding"}
)
# Notes every session may carry (the prior, the bag, samples cleaned); a valid run with only these is not flagged.
ROUTINE = frozenset(
    {"prior_note", "bag_note", "timing_note", "tare_note", "data_note", "held_from_check"}
    | {"wrench_spikes_removed", "fit_outliers_removed"}
)


@dataclass(frozen=True)
class Case:
    """One row: the motion, whether the arm has joint springs, the patient."""

    name: str
    motion: str  # "0.03", "0.12" (paper sine, shoulder peak rad/s), "0.03/0.12" (slow half, fast half) or "plan"
    springs: bool
    patient: Patient


def cases() -> list[Case]:
    """Every case, in table order (names are :data:`CAUSES`'s keys)."""
    activity = [
        Case(f"activity_{p}", "0.03", False, Patient(activity=InvoluntaryActivity(share_of_gravity=p / 100)))
        for p in (2, 5, 10, 20)
    ]
    return [
        Case("control_paper", "0.03", False, Patient()),
        Case("control_plan", "plan", False, Patient()),
        Case("control_fast", "0.12", False, Patient()),
        *activity,
        # 7 % activity with the muscles' EMG envelopes and a 4 s co-contraction without net torque (mujoco_emg.py).
        Case(
            "activity_emg",
            "0.03",
            False,
            Patient(activity=InvoluntaryActivity(share_of_gravity=0.07), emg=EmgRecording(cocontraction_s=4.0)),
        ),
        Case("spasticity_slow", "0.03", False, Patient(spasticity=Spasticity())),
        Case("spasticity_fast", "0.12", False, Patient(spasticity=Spasticity())),
        Case("stroke_arm", "0.03", True, typical_stroke_arm()),
        Case("skin_sliding", "0.03", False, Patient(skin=SkinSliding())),
        Case("tremor_joints", "0.03", False, Patient(tremor=Tremor())),
        Case("tremor_handle", "0.03", False, Patient(tremor=Tremor(site=TremorSite.HANDLE))),
        Case("hand_slip", "0.03", False, Patient(slip=HandSlip())),
        Case("compliant_strap", "0.03", False, Patient(strap=CompliantStrap())),
        Case("control_two_speed", "0.03/0.12", False, Patient()),
        Case("spasticity_two_speed", "0.03/0.12", False, Patient(spasticity=Spasticity())),
    ]


@dataclass(kw_only=True)
class Tally(Counts):
    """One case's runs: :class:`scoring.Counts`, both other outcomes, the cause-naming counts and the codes seen."""

    # An invalid estimate without a scored parameter counts as invalid-and-right here (every |z| <= 3 holds).
    UNSCORED_INVALID_RIGHT = True

    valid_right: int = 0
    invalid_wrong: int = 0
    flagged: int = 0
    named: int = 0
    quiet_runs: int = 0
    false_alarms: int = 0
    codes: collections.Counter[str] = field(default_factory=collections.Counter)

    def add(self, estimate: dict[str, Any], truth: dict[str, Any], causes: frozenset[str]) -> dict[str, Any]:
        """Score one estimate; return its row (valid, worst |z|, codes, flagged, named).

        ``causes`` empty: the run had no cause (a control, a reflex that never fired); it counts as quiet, and as
        a false alarm if a patient-cause code shows.
        """
        run = self.score(estimate, truth)
        valid, wrong = run.valid, run.wrong
        self.valid_right += valid and not wrong
        self.invalid_wrong += (not valid) and wrong
        findings = estimate["quality"].get("findings", [])
        codes = sorted({str(f["code"]) for f in findings})
        flagged = (not valid) or any(f["severity"] == "weak" or f["code"] not in ROUTINE for f in findings)
        named = bool(causes & set(codes))
        if causes:
            self.flagged += flagged
            self.named += flagged and named
        else:
            self.quiet_runs += 1
            self.false_alarms += bool(PATIENT_CODES & set(codes))
        self.codes.update(c for c in codes if c not in ROUTINE)
        worst_z = run.max_z if run.z else 0.0
        return {"valid": valid, "wrong": wrong, "worst_z": worst_z, "worst": run.worst, "codes": codes}

    def naming(self) -> str:
        """``named/flagged`` and its share over the runs with a cause; ``false n/m``: of the runs without one, those
        naming some patient cause."""
        parts = []
        if self.flagged:
            parts.append(f"{self.named}/{self.flagged} {100 * self.named / self.flagged:3.0f}%")
        elif self.runs > self.quiet_runs:
            parts.append("0/0")
        if self.quiet_runs:
            parts.append(f"false {self.false_alarms}/{self.quiet_runs}")
        return " ".join(parts)

    def to_json(self) -> dict[str, Any]:
        return {
            **{
                k: getattr(self, k)
                for k in ("runs", "valid_right", "valid_wrong", "invalid_right", "invalid_wrong", "failed")
            },
            **{k: getattr(self, k) for k in ("flagged", "named", "quiet_runs", "false_alarms")},
            "worst_z": self.worst_z,
            "worst_param": self.worst_param,
            "naming": self.naming(),
            "calibration": dataclasses.asdict(self.two_sided.calibration()),
            "codes": dict(self.codes),
        }


def cause_imposed(truth: dict[str, Any]) -> bool:
    """Whether the patient of truth.json did anything: a reflex that never fired (a stretch below its threshold
    speed) leaves the run without a cause to name."""
    patient = truth.get("patient", {})
    acting = [k for k in ("activity", "tremor", "skin", "slip", "strap") if k in patient]
    reflex = patient.get("spasticity", {}).get("active_fraction", 0.0) > 0.0
    return bool(acting) or reflex


def session_bag(case: Case, seed: int, args: argparse.Namespace, workdir: Path, out_dir: Path) -> Path:
    """Simulate ``case`` with ``seed`` and write its bag (and truth.json) to ``out_dir``."""
    if case.motion == "plan":
        trajectory: Any = planned_trajectory_from_file(planned_in_ranges(workdir, args.duration))
    elif "/" in case.motion:
        slow, fast = (float(x) for x in case.motion.split("/"))
        trajectory = TwoSpeedPath(paper_sine(slow), (1.0, fast / slow), args.duration / 2, args.duration)
    else:
        trajectory = paper_sine(float(case.motion))
    options = CellOptions(trajectory=trajectory, duration_s=args.duration, wrench_hz=args.wrench_hz, seed=seed)
    session = patient_session(draw_arm(seed, springs=case.springs), options, case.patient)
    if isinstance(trajectory, TwoSpeedPath):
        session.cell.truth["speed_dependence"] = speed_part_truth(session.imposed, trajectory)
    return write_bag(out_dir, session.cell)


def speed_part_truth(imposed: Imposed, path: TwoSpeedPath) -> dict[str, Any]:
    """The elbow's imposed speed-dependent part per direction of motion, averaged as the estimator averages it: the
    reflex torque's mean over the fast half's samples (after the rate's change) moving in that direction faster than
    the estimator's direction deadband (a tenth of the joint's 95th percentile speed), Nm."""
    velocity = path.velocities_rad_s(imposed.t_s)[:, ELBOW]
    fast = imposed.t_s > path.start_s + path.ramp_s
    moving = np.abs(velocity) > 0.1 * np.percentile(np.abs(velocity), 95)
    parts = {
        name: float(imposed.reflex_nm[fast & moving & (sign * velocity > 0), ELBOW].mean())
        for name, sign in (("positive", 1.0), ("negative", -1.0))
    }
    return {"elbow": parts}


def speed_part_scores(estimate: dict[str, Any], truth: dict[str, Any]) -> dict[str, Any]:
    """Per joint and direction of truth.json's ``speed_dependence``: the estimate's part, its std, the truth and
    z = (estimate - truth) / std; an empty dict where the estimate has no such block or the truth none."""
    found = estimate.get("speed_dependence") or {}
    out: dict[str, Any] = {}
    for joint, parts in (truth.get("speed_dependence") or {}).items():
        for direction, true_nm in parts.items():
            part = found.get(joint, {}).get(direction)
            if part is None:
                out[f"{joint}/{direction}"] = {"truth_nm": true_nm, "measured": False}
                continue
            z = (part["part_nm"] - true_nm) / part["std_nm"] if part["std_nm"] else float("inf")
            out[f"{joint}/{direction}"] = {**part, "truth_nm": true_nm, "z": z}
    return out


def run_case(case: Case, seeds: list[int], args: argparse.Namespace, workdir: Path) -> tuple[Tally, list[dict]]:
    """Simulate and identify ``case`` once per seed."""
    tally, rows = Tally(), []
    extra = ("--passive", args.passive) if args.passive else ()
    for seed in seeds:
        bag = session_bag(case, seed, args, workdir, workdir / f"{case.name}_{seed}")
        truth = json.loads((bag / "truth.json").read_text())
        code, estimate = identify(bag, workdir / f"{case.name}_{seed}.json", *extra)
        if not estimate:
            tally.count_failure()
            rows.append({"case": case.name, "seed": seed, "exit": code})
            continue
        row = tally.add(estimate, truth, CAUSES[case.name] if cause_imposed(truth) else frozenset())
        speed = speed_part_scores(estimate, truth)
        rows.append({"case": case.name, "seed": seed, "exit": code, **row, **({"speed_part": speed} if speed else {})})
        if args.verbose:
            print(f"  seed {seed}: valid={row['valid']} worst |z| {row['worst_z']:.2f} ({row['worst']}) {row['codes']}")
        for key, part in speed.items():
            measured = (
                f"{part['part_nm']:+.4f} +- {part['std_nm']:.4f} Nm (z vs truth {part['z']:+.2f}, from 0 "
                f"{part['part_nm'] / part['std_nm']:+.1f} std)"
                if "part_nm" in part
                else "not measured"
            )
            print(f"  seed {seed}: speed-dependent part {key}: {measured}, truth {part['truth_nm']:.4f} Nm")
    return tally, rows


HEADER = (
    f"{'case':16} runs  v&right V&WRONG inv&right inv&wrong {calibration.calibration_header()}  "
    f"{'names cause':13} worst|z| (parameter)  codes beyond routine"
)


def row_text(name: str, t: Tally) -> str:
    """One table row of a case."""
    codes = ", ".join(f"{c} {n}" for c, n in t.codes.most_common(4)) or "-"
    fail = f" failed {t.failed}" if t.failed else ""
    return (
        f"{name:16} {t.runs:4} {t.valid_right:8} {t.valid_wrong:7} {t.invalid_right:9} {t.invalid_wrong:9} "
        f"{calibration.calibration_columns(t.two_sided.calibration())}  {t.naming():13} "
        f"{t.worst_z:8.3g} ({t.worst_param})  {codes}{fail}"
    )


def write_bags(selected: list[Case], args: argparse.Namespace) -> int:
    """``--write-bags``: one bag per case with the first seed into ``DIR/<case>/``."""
    args.write_bags.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix="patients_") as tmp:
        for case in selected:
            out = args.write_bags / case.name
            if out.exists():
                print(f"{out} exists: left as it is")
                continue
            bag = session_bag(case, args.first_seed, args, Path(tmp), out)
            print(f"wrote {bag}", flush=True)
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--duration", type=float, default=120.0, help="recorded session length, s")
    parser.add_argument("--wrench-hz", type=float, default=1000.0)
    parser.add_argument("--quick", action="store_true", help="2 seeds of 60 s, wrench at 250 Hz")
    parser.add_argument("--only", default="", help="only cases whose name contains this (e.g. activity, stroke_arm)")
    parser.add_argument("--passive", default="", metavar="MODEL", help="bsp identify --passive MODEL (e.g. auto)")
    parser.add_argument("--json", type=Path, help="write the table and every run as JSON here")
    parser.add_argument("--write-bags", type=Path, metavar="DIR", help="write one bag per case to DIR, identify none")
    parser.add_argument("--verbose", action="store_true", help="every run's worst |z| and codes")
    args = parser.parse_args(argv)
    if args.quick:
        args.seeds, args.duration, args.wrench_hz = min(args.seeds, 2), 60.0, 250.0
    selected = [c for c in cases() if args.only in c.name]
    if not selected:
        parser.error(f"--only {args.only!r} matches no case (cases: {', '.join(CAUSES)})")
    if args.write_bags is not None:
        return write_bags(selected, args)
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    tallies: dict[str, Tally] = {}
    runs: list[dict] = []
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="patients_") as tmp:
        for case in selected:
            print(f"{case.name} ...", flush=True)
            tallies[case.name], rows = run_case(case, seeds, args, Path(tmp))
            runs.extend(rows)
            print("  " + row_text(case.name, tallies[case.name]), flush=True)
    model = args.passive or "default"
    print(
        f"\n{len(seeds)} seeds, {args.duration:g} s, wrench {args.wrench_hz:g} Hz, passive {model}, "
        f"{time.monotonic() - start:.0f} s"
    )
    print("calibration over the valid runs' data-sourced parameters; names cause: of the invalid or flagged runs")
    print(HEADER)
    for name, t in tallies.items():
        print(row_text(name, t))
    if args.json:
        document = {
            "settings": {"seeds": seeds, "duration_s": args.duration, "wrench_hz": args.wrench_hz, "passive": model},
            "cases": {k: t.to_json() for k, t in tallies.items()},
            "runs": runs,
        }
        args.json.write_text(json.dumps(document, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
