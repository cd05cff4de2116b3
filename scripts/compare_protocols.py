#!/usr/bin/env python3
"""The method paper's protocol and a planned one side by side: predicted std of every parameter.

Both for the simulator's default human arm (de Leva table, 75 kg, 1.78 m), 120 s, the simulator's default
sensor noise (force 0.05 N, moment 0.005 Nm, markers 0.1 mm; wrench 100 Hz, markers 50 Hz), and the passive
model ``coulomb+offset+stiffness``. The paper's protocol is the simulator's default trajectory (+-6 deg at the
shoulder, +-1.7 deg at the elbow, +-0.9 deg at the wrist about one operating point). The planned one is
``bsp plan`` within shoulder -70..-10 deg, elbow 10..100 deg, wrist -20..20 deg and 0.03 rad/s.

Run: ``python scripts/compare_protocols.py [--simulate SEEDS]`` (with --simulate, also the std achieved over
that many simulated sessions of each protocol, with the issue's passive truth).
"""

from __future__ import annotations

import argparse

import numpy as np

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.planning import JointLimits, NominalArm, PlanRequest, plan_protocol, predict_covariance

MODEL = PassiveModel.parse("coulomb+offset+stiffness")
RANGES_DEG = ((-70.0, -10.0), (10.0, 100.0), (-20.0, 20.0))
TRUTH = sim.PassiveTruth(coulomb_nm=(0.5, 0.28, 0.06), offset_nm=(0.2, 0.2, 0.2), stiffness_nm_per_rad=(0.0, 1.5, 0.0))


def _scatter(trajectory: object, seeds: int) -> tuple[np.ndarray, int, int]:
    values, valid, flagged = [], 0, 0
    for seed in range(seeds):
        session = sim.simulate_cell(sim.human_arm_cell(seed=seed, passive=TRUTH, trajectory=trajectory))
        result = identify_joint(identification_data_from_session(session.session), JointConfig(passive=MODEL))
        values.append(result.values)
        valid += result.valid
        flagged += any(f.code is FindingCode.CONFOUNDED for f in result.findings)
    return np.array(values).std(axis=0, ddof=1), valid, flagged


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--simulate", type=int, default=0, metavar="SEEDS", help="also simulate SEEDS sessions each")
    args = parser.parse_args()
    base = sim.human_arm_cell()
    nominal = NominalArm.from_anthropometry(base.subject.lengths_m)
    paper = predict_covariance(base.trajectory, 120.0, nominal, MODEL)
    plan = plan_protocol(PlanRequest(nominal=nominal, shoulder_yz_m=(0.0, 1.2), limits=JointLimits(RANGES_DEG)))
    print("paper protocol: one operating point (-43.3, 29.5, 0.2) deg, amplitudes (6, 1.7, 0.9) deg")
    centres = "; ".join("(" + ", ".join(f"{v:.1f}" for v in row) + ")" for row in plan.centres_deg)
    amplitudes = ", ".join(f"{a:.1f}" for a in plan.amplitudes_deg)
    speeds = ", ".join(f"{v:.4f}" for v in plan.trajectory.peak_speed_rad_s)
    print(f"planned protocol: operating point(s) {centres} deg, amplitudes ({amplitudes}) deg,")
    print(f"  peak speeds ({speeds}) rad/s")
    ratio = ", ".join(f"{100 * r:.2f}%" for r in plan.inertia_ratio)
    print(
        f"planned: inertial / gravity torque ({ratio}); condition number paper {paper.condition_number:.0f}, "
        f"planned {plan.prediction.condition_number:.0f}"
    )
    header = f"{'parameter':32s} {'nominal':>8s} {'paper std':>10s} {'planned std':>11s} {'gain':>6s}"
    achieved: dict[str, tuple[np.ndarray, int, int]] = {}
    if args.simulate:
        achieved = {"paper": _scatter(base.trajectory, args.simulate), "plan": _scatter(plan.trajectory, args.simulate)}
        header += f" {'paper achieved':>14s} {'planned achieved':>16s}"
    print(header)
    for i, (key, owner) in enumerate(paper.names):
        nominal_value = paper.nominal[i]
        text = f"{nominal_value:.4g}" if np.isfinite(nominal_value) else ""
        line = (
            f"{key + '/' + owner:32s} {text:>8s} {paper.std[i]:10.3g} {plan.prediction.std[i]:11.3g} "
            f"{paper.std[i] / plan.prediction.std[i]:6.0f}"
        )
        if achieved:
            line += f" {achieved['paper'][0][i]:14.3g} {achieved['plan'][0][i]:16.3g}"
        print(line)
    for name in achieved:
        _, valid, flagged = achieved[name]
        print(f"{name}: {valid}/{args.simulate} valid, {flagged}/{args.simulate} flagged confounded")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
