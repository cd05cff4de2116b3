"""Predicted std of `bsp plan` against the std `bsp identify` reports on sessions that follow the plan.

Per case (a plan request) the plan is made once; then per seed one session that follows it is simulated (the
table arm with the cell's Coulomb friction and nonlinear, coupled elastic moments, markers re-placed uniformly
within +-3.46 mm of the joint centres, which is identify's assumed 2 mm sd; an untared sensor whose zero is
exact, or with ``tared`` a simulated tare recording) and identified with the plan's passive model, as

    bsp simulate --out S --trajectory PLAN.json --seed N --skin-offset-mm 3.46 [--stiffness ...]
    bsp identify S --passive MODEL [--tare TARE.yaml]

would (the library calls behind them, so the nonlinear passive truth of the plan's own simulated check can be
used). Printed: per case and parameter the predicted std, the reported std per seed, the ratio reported /
predicted and each budget's largest term; the worst ratio per case and how many ratios lie within 1.5x either
way (the target). With ``auto`` also the model identify chose per seed and the one the plan predicts for (chosen on
its own simulated session of the nominal arm).

Run: ``nice -n 10 python bench/plan_vs_identify.py [--seeds 3] [--first-seed 0] [--cases default fast auto tared]``.
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace
from typing import Any

import numpy as np

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.pipeline import IdentifyOptions, identify_recordings
from bsp_ros.core.planning import JointLimits, NominalArm, PlanRequest, plan_protocol
from bsp_ros.core.planning.budget import SessionSpec
from bsp_ros.core.planning.compare import compare_budget_with_estimate
from bsp_ros.core.planning.planner import Plan
from bsp_ros.core.planning.simulated import plan_cell_spec, plan_passive_truth, simulated_recordings
from bsp_ros.core.tare.estimate import estimate_tare

SHOULDER_YZ_M = (0.0, 1.2)
RANGES_DEG = ((-70.0, -10.0), (10.0, 100.0), (-20.0, 20.0))
# Uniform within +-b per axis has sd b / sqrt(3): identify's assumed 2 mm.
SKIN_BOUND_M = 0.002 * math.sqrt(3.0)
TARGET_RATIO = 1.5
VERBOSE = False


def case_request(name: str) -> PlanRequest:
    """The plan request of a named case: ``default`` (bsp plan's defaults), ``fast`` (60 s at twice the speed),
    ``auto`` (``--passive auto``), ``tared`` (the default, tared)."""
    subject = sim.human_arm_cell().subject
    base = PlanRequest(
        nominal=NominalArm.from_anthropometry(subject.lengths_m),
        shoulder_yz_m=SHOULDER_YZ_M,
        limits=JointLimits(RANGES_DEG),
    )
    if name == "fast":
        return replace(base, duration_s=60.0, limits=JointLimits(RANGES_DEG, 0.06))
    if name == "auto":
        return replace(base, passive=PassiveModel.parse("auto"))
    if name == "tared":
        return replace(base, session=SessionSpec(tared=True))
    return base


def simulated_estimate(plan: Plan, seed: int) -> dict[str, Any]:
    """The estimate document `bsp identify` gives of one simulated session that follows ``plan``."""
    subject = sim.SubjectTruth.from_anthropometry("male", 75.0, 1.78, plan.request.nominal.n_joints)
    passive = plan_passive_truth(plan)
    if not plan.request.passive.select:
        # A fixed model's std is that of a valid estimate: the truth within the model (linear springs).
        passive = replace(passive, stiffening_nm=(0.0,) * len(passive.coulomb_nm), biarticular_nm=0.0)
    sessions = [cell.session for cell in simulated_recordings(plan, subject, passive, seed, SKIN_BOUND_M)]
    tare = simulated_tare(plan_cell_spec(plan, subject, passive, seed=seed)) if plan.request.session.tared else None
    options = IdentifyOptions(passive=plan.request.passive, tare=tare)
    return identify_recordings(sessions, options, trunk_tilts_rad=plan.request.trunk_tilts_rad)


def simulated_tare(spec: Any) -> Any:
    """The tare `bsp tare` makes of the cell's tare recording (the sensor at rest, 20 s before the session)."""
    wrench = sim.simulate_tare(spec).wrench
    return estimate_tare(wrench.t_ns, wrench.force_n, wrench.torque_nm, wrench.frame_id)


def compare_case(name: str, seeds: list[int]) -> tuple[float, int, int]:
    """Print the case's comparison; return its worst ratio (the larger of reported / predicted and its inverse),
    and how many of its ratios lie within :data:`TARGET_RATIO` either way, of how many."""
    started = time.perf_counter()
    plan = plan_protocol(case_request(name))
    planned_s = time.perf_counter() - started
    assert plan.budget is not None
    estimates = [simulated_estimate(plan, seed) for seed in seeds]
    valid = [bool(estimate["quality"]["valid"]) for estimate in estimates]
    rows_by_seed = [compare_budget_with_estimate(plan.budget, e) for e, ok in zip(estimates, valid, strict=True) if ok]
    label = plan.request.passive.label
    print(f"\n== {name}: --passive {label}, {plan.request.duration_s:g} s, planned in {planned_s:.1f} s; valid {valid}")
    if plan.auto_choice is not None:
        chosen = [str(e["diagnostics"].get("passive_model")) for e in estimates]
        print(f"predicted for {plan.auto_choice.chosen.label} (the plan's check); identify chose per seed {chosen}")
    if not rows_by_seed:
        return math.inf, 0, 0
    if VERBOSE:
        for estimate in estimates:
            budgets = {s: q["static_moment_kgm"].get("budget") for s, q in estimate["segments"].items()}
            print({s: {t: round(v, 5) for t, v in (b or {}).items()} for s, b in budgets.items()})
        print([{t: round(v, 5) for t, v in plan.budget.contributions(i).items()} for i in range(3)])
    print(f"{'parameter':34s} {'predicted':>10s} {'largest':>17s}  reported / ratio per seed")
    worst, within, total = 1.0, 0, 0
    for row in rows_by_seed[0]:
        name_ = f"{row['quantity']}/{row['owner']}"
        others = [
            next((r for r in rows if r["quantity"] == row["quantity"] and r["owner"] == row["owner"]), None)
            for rows in rows_by_seed
        ]
        cells = []
        for other in others:
            if other is None:
                cells.append("-")
                continue
            worst = max(worst, other["ratio"], 1.0 / other["ratio"])
            within += int(1.0 / TARGET_RATIO <= other["ratio"] <= TARGET_RATIO)
            total += 1
            cells.append(f"{other['reported_std']:.3g} ({other['ratio']:.2f}, {other['reported_largest']})")
        print(f"{name_:34s} {row['predicted_std']:10.3g} {row['predicted_largest']:>17s}  " + "; ".join(cells))
    print(f"worst ratio {worst:.2f}; {within} of {total} ratios within {TARGET_RATIO:g}x")
    return worst, within, total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3, help="sessions per case (default 3)")
    parser.add_argument("--first-seed", type=int, default=0, help="seed of the first session (default 0)")
    parser.add_argument("--cases", nargs="+", default=["default", "fast", "auto", "tared"])
    args = parser.parse_args()
    seeds = list(range(args.first_seed, args.first_seed + args.seeds))
    found = {name: compare_case(name, seeds) for name in args.cases}
    print(
        "\nworst ratio per case: "
        + ", ".join(f"{name} {worst:.2f} ({within}/{total} within)" for name, (worst, within, total) in found.items())
    )


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
