#!/usr/bin/env python3
"""Predicted std of a planned protocol against the scatter of 20 seeded simulated sessions.

Plans a 120 s protocol for the simulator's default human arm, simulates it with 20 seeds (elastic offsets
0.2 Nm and a stiffness at every joint, so no estimate sits at a bound), identifies each session with
``--passive coulomb+offset+stiffness``, and prints per parameter the predicted std, the scatter of the
estimates, the mean reported (HAC) std, their ratios, and how often the truth lies within 3 reported std.

Run: ``python scripts/plan_std_sweep.py [--seeds 20]``
"""

from __future__ import annotations

import argparse

import numpy as np

from bsp_ros.core import simulation as sim
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.planning import JointLimits, NominalArm, PlanRequest, compare_with_scatter, plan_protocol

PASSIVE = sim.PassiveTruth(
    coulomb_nm=(0.5, 0.28, 0.06), offset_nm=(0.2, 0.2, 0.2), stiffness_nm_per_rad=(1.0, 1.5, 0.2)
)
RANGES_DEG = ((-70.0, -10.0), (10.0, 100.0), (-20.0, 20.0))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="number of seeded sessions (default 20)")
    args = parser.parse_args()
    base = sim.human_arm_cell()
    model = PassiveModel.parse("coulomb+offset+stiffness")
    plan = plan_protocol(
        PlanRequest(
            nominal=NominalArm.from_anthropometry(base.subject.lengths_m),
            shoulder_yz_m=(0.0, 1.2),
            limits=JointLimits(RANGES_DEG),
        )
    )
    results, truths = [], None
    for seed in range(args.seeds):
        session = sim.simulate_cell(sim.human_arm_cell(seed=seed, passive=PASSIVE, trajectory=plan.trajectory))
        result = identify_joint(identification_data_from_session(session.session), JointConfig(passive=model))
        results.append(result)
        truths = session.truth.to_dict()
    assert truths is not None
    rows = compare_with_scatter(plan.prediction, results)
    values = np.array([r.values for r in results])
    stds = np.array([r.std for r in results])
    print(f"{args.seeds} sessions of {plan.trajectory.duration_s:.0f} s; valid: {sum(r.valid for r in results)}")
    print(
        f"{'parameter':34s} {'truth':>9s} {'mean':>9s} {'predicted':>10s} {'scatter':>10s} {'reported':>10s} "
        f"{'scat/pred':>9s} {'rep/pred':>8s} {'|z|<3':>6s}"
    )
    worst = 1.0
    for i, row in enumerate(rows):
        key, owner = str(row["quantity"]), str(row["owner"])
        table = truths["segments"] if owner in truths["segments"] else truths["joints"]
        truth = float(table[owner][key])
        within = float(np.mean(np.abs(values[:, i] - truth) < 3 * stds[:, i]))
        ratio = float(row["ratio"])
        worst = max(worst, ratio, 1 / ratio)
        print(
            f"{key + '/' + owner:34s} {truth:9.4g} {values[:, i].mean():9.4g} {row['predicted_std']:10.3g} "
            f"{row['achieved_std']:10.3g} {row['reported_std']:10.3g} {ratio:9.2f} "
            f"{float(row['reported_std']) / float(row['predicted_std']):8.2f} {within:6.2f}"
        )
    print(f"worst factor between predicted std and scatter: {worst:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
