"""Coverage and warning false-alarm rates of `bsp identify` over seeded simulated sessions.

For each seed and scenario a human arm cell is simulated and identified (joint method, defaults). Reported:
the share of valid estimates, for valid ones the share of data-sourced parameters whose truth lies within
3 std, both error rates per session (valid-and-wrong: valid, some data-sourced parameter beyond 3 std;
invalid-and-right: invalid, every one within 3 std), how often each kind of warning fires and what made the
invalid ones invalid (a kind: a finding's code with its joint or segment, ``bench/finding_kinds.py``). Two-sided
calibration (``bench/calibration.py``) over the data-sourced parameters of valid estimates: z RMS (1 for an
honest std), the shares within 1 and 2 std (68 %, 95 % for an honest std), and per parameter kind (static
moments, Coulomb amplitudes, masses) the sharpness, median and range over the parameters of the median std over
the RMS error across the scenario's sessions (1 ideal; one arm with re-placed markers in the skin scenarios,
one arm re-simulated by seed in the others, not given for random_subject, whose arm changes by seed). Run:

    python bench/coverage.py --sessions 200 --duration 120 --scenario clean
    python bench/coverage.py --sessions 50 --scenario elastic

Scenarios: clean; elastic (0.2 Nm passive offset per joint) and elastic_small (0.05 Nm); random_subject
(body mass 55-100 kg drawn from the prior); dropouts (5% marker dropouts, 20 frames mean); glitches (one
elbow frame off by ~0.3 m and ten 1 kN wrench spikes); transition_1mrad / transition_2mrad (Coulomb
friction as c tanh(v / w), added to the torques of a friction-free session); skin_3mm (every marker re-placed
within +-3 mm of its joint centre per axis, drawn anew per session) and skin_3mm_planned (the same on the
planner's protocol for shoulder -70..-10, elbow 10..100, wrist -20..20 deg, in place of the sines);
fast_inertia_plan (the same re-placed markers on ``bsp plan --excite-inertia --max-speed 0.15``'s two sines per
joint for those ranges: inertial torques 1.5-2.5 % of gravity, grouped inertias identified from the data).
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import functools
import json
import time
from typing import Any

import numpy as np
from calibration import calibration_columns, calibration_header, sharpness_columns, sharpness_header, summary_line
from finding_kinds import cause_of, warning_kinds
from scoring import Counts

from bsp_ros.core import glitches
from bsp_ros.core import simulation as sim
from bsp_ros.core.estimate import estimate_document
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.pipeline import IdentifyOptions, fuse, identify_data, identify_session

SCENARIOS = (
    "clean",
    "elastic",
    "elastic_small",
    "random_subject",
    "dropouts",
    "glitches",
    "transition_1mrad",
    "transition_2mrad",
    "skin_3mm",
    "skin_3mm_planned",
    "fast_inertia_plan",
)
SKIN_BOUND_M = 0.003  # markers re-placed within +-3 mm of the joint centres, anew every session
COULOMB_NM = np.array([0.5, 0.28, 0.06])


def _spec(scenario: str, seed: int, duration_s: float) -> sim.CellSpec:
    rng = np.random.default_rng(10_000 + seed)
    spec = sim.human_arm_cell(seed=seed, duration_s=duration_s)
    if scenario == "random_subject":
        subject = sim.SubjectTruth.from_anthropometry("male", float(rng.uniform(55, 100)), 1.78, 3, rng=rng)
        spec = dataclasses.replace(spec, subject=subject)
    if scenario == "dropouts":
        spec = dataclasses.replace(
            spec, markers=dataclasses.replace(spec.markers, dropout_fraction=0.05, dropout_mean_frames=20.0)
        )
    if scenario.startswith("transition"):
        spec = dataclasses.replace(spec, passive=sim.PassiveTruth(coulomb_nm=(0.0, 0.0, 0.0)))
    if scenario.startswith("skin"):
        spec = dataclasses.replace(spec, markers=dataclasses.replace(spec.markers, skin_offset_bound_m=SKIN_BOUND_M))
    if scenario.endswith("planned"):
        spec = dataclasses.replace(spec, trajectory=_plan().trajectory)
    if scenario == "fast_inertia_plan":
        spec = dataclasses.replace(
            spec,
            trajectory=_inertia_plan().trajectory,
            markers=dataclasses.replace(spec.markers, skin_offset_bound_m=SKIN_BOUND_M),
        )
    if scenario.startswith("elastic"):
        offset = 0.2 if scenario == "elastic" else 0.05
        passive = dataclasses.replace(spec.passive, offset_nm=(offset, offset, offset))
        spec = dataclasses.replace(spec, passive=passive)
    return spec


@functools.cache
def _plan() -> Any:
    """`bsp plan`'s default protocol for the simulator's subject (ranges of bsp plan's help example)."""
    from bsp_ros.core.planning import JointLimits, NominalArm, PlanRequest, plan_protocol

    nominal = NominalArm.from_anthropometry(sim.human_arm_cell().subject.lengths_m)
    limits = JointLimits(((-70.0, -10.0), (10.0, 100.0), (-20.0, 20.0)))
    return plan_protocol(PlanRequest(nominal=nominal, shoulder_yz_m=(0.0, 1.2), limits=limits))


@functools.cache
def _inertia_plan() -> Any:
    """`bsp plan --excite-inertia --max-speed 0.15`'s protocol for the same ranges (two sines per joint)."""
    from bsp_ros.core.planning import JointLimits, NominalArm, PlanRequest, plan_inertia_protocol

    nominal = NominalArm.from_anthropometry(sim.human_arm_cell().subject.lengths_m)
    limits = JointLimits(((-70.0, -10.0), (10.0, 100.0), (-20.0, 20.0)), 0.15)
    return plan_inertia_protocol(PlanRequest(nominal=nominal, shoulder_yz_m=(0.0, 1.2), limits=limits), 0.3)


def _transition_document(spec: sim.CellSpec, simulated: sim.SimulatedSession, width_rad_s: float) -> dict[str, Any]:
    """Friction ``c tanh(v / width)`` added to the torques of a friction-free session (the true velocities)."""
    data = identification_data_from_session(simulated.session)
    simulator = sim.CellSimulator(spec)
    velocity = simulator.joint_velocities_rad_s(simulator.seconds_since_start(data.t_ns))
    data = dataclasses.replace(data, tau_nm=data.tau_nm + COULOMB_NM * np.tanh(velocity / width_rad_s))
    options = IdentifyOptions()
    result = identify_data(data, options)
    posterior = fuse(result, data, options.subject) if result.valid else None
    return estimate_document(
        result, data, posterior, options.subject, marker_placement_sd_m=options.marker_placement_sd_m
    )


def run(scenario: str, sessions: int, duration_s: float, first_seed: int) -> dict[str, Any]:
    z_all: list[float] = []
    worst: list[tuple[float, int, str]] = []
    kinds: collections.Counter[str] = collections.Counter()
    causes: collections.Counter[str] = collections.Counter()
    counts = Counts()
    started = time.perf_counter()
    for seed in range(first_seed, first_seed + sessions):
        spec = _spec(scenario, seed, duration_s)
        simulated = sim.simulate_cell(spec)
        truth = simulated.truth.to_dict()
        if scenario == "glitches":
            rng = np.random.default_rng(seed)
            session = glitches.displace_marker(
                simulated.session, "elbow", int(rng.integers(100, 2900)), rng.normal(0.0, 0.3, 3)
            )
            session = glitches.wrench_spikes(session, 10, 1000.0, seed=seed)
            document = identify_session(session)
        elif scenario.startswith("transition"):
            document = _transition_document(spec, simulated, 0.001 if scenario.endswith("1mrad") else 0.002)
            for j, joint in enumerate(("shoulder", "elbow", "wrist")):
                truth["joints"][joint]["coulomb_nm"] = float(COULOMB_NM[j])
        else:
            document = identify_session(simulated.session)
        # Each kind once, in the order the findings give them (a set's order changes with the hash seed).
        for kind in dict.fromkeys(warning_kinds(document["quality"])):
            kinds[kind] += 1
        scored = counts.score(document, truth)
        if not scored.valid:
            causes[cause_of(document["quality"])] += 1
            continue
        for name, z_value in scored.z.items():
            z_all.append(z_value)
            worst.append((z_value, seed, name))
    z = np.array(z_all)
    two_sided = counts.two_sided.calibration()
    # Sharpness compares one parameter across sessions: meaningful only while the arm stays the same.
    sharp = {} if scenario == "random_subject" else counts.two_sided.sharpness()
    return {
        "scenario": scenario,
        "sessions": sessions,
        "duration_s": duration_s,
        "valid": counts.valid,
        "parameters": int(z.size),
        "within_3_std": float((z < 3).mean()) if z.size else None,
        "z_rms": two_sided.z_rms if two_sided.count else None,
        "within_1_std": two_sided.within_1 if two_sided.count else None,
        "within_2_std": two_sided.within_2 if two_sided.count else None,
        "sharpness": {kind: dataclasses.asdict(spread) for kind, spread in sharp.items()},
        "valid_and_wrong": counts.valid_wrong,
        "invalid_and_right": counts.invalid_right,
        "worst": sorted(worst, reverse=True)[:5],
        "warning_rate": {k: v / sessions for k, v in kinds.most_common()},
        "invalid_reasons": dict(causes),
        "seconds": round(time.perf_counter() - started, 1),
        "counts": counts,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, default=200)
    parser.add_argument("--duration", type=float, default=120.0)
    parser.add_argument(
        "--scenario", choices=(*SCENARIOS, "all"), default="clean", help="all: every scenario, and the pooled coverage"
    )
    parser.add_argument("--first-seed", type=int, default=0)
    args = parser.parse_args()
    if args.scenario != "all":
        result = run(args.scenario, args.sessions, args.duration, args.first_seed)
        counts = result.pop("counts")
        print(json.dumps(result, indent=1))
        print(summary_line(args.scenario, counts.two_sided, sharpness=args.scenario != "random_subject"))
        return
    results = [run(scenario, args.sessions, args.duration, args.first_seed) for scenario in SCENARIOS]
    print(
        f"{'scenario':18s} {'valid':>9s} {'parameters':>10s} {'within 3 std':>12s} {'worst |z|':>9s}"
        f" {'v&wrong':>7s} {'inv&right':>9s} {calibration_header()} {sharpness_header()}"
    )
    pooled = Counts()
    for r in results:
        within = "-" if r["within_3_std"] is None else f"{100 * r['within_3_std']:.2f} %"
        worst = f"{r['worst'][0][0]:.2f}" if r["worst"] else "-"
        counts = r.pop("counts")
        pooled.pool(counts)
        sharp = sharpness_columns(counts.two_sided.sharpness()) if r["sharpness"] else sharpness_columns({})
        print(
            f"{r['scenario']:18s} {counts.valid:>4d}/{counts.runs:<4d} {r['parameters']:>10d} {within:>12s}"
            f" {worst:>9s} {counts.valid_wrong:>7d} {counts.invalid_right:>9d}"
            f" {calibration_columns(counts.two_sided.calibration())} {sharp}"
        )
    parameters = sum(r["parameters"] for r in results)
    inside = sum(r["parameters"] * (r["within_3_std"] or 0.0) for r in results)
    sessions, valid = pooled.runs, pooled.valid
    wrong, thrown = pooled.valid_wrong, pooled.invalid_right
    print(
        f"valid-and-wrong {wrong}/{sessions} sessions ({100 * wrong / sessions:.1f} %), "
        f"invalid-and-right {thrown}/{sessions} ({100 * thrown / sessions:.1f} %)"
    )
    print(
        f"pooled: {valid}/{sessions} sessions valid, {parameters} data-sourced parameters of valid estimates,"
        f" {100 * inside / max(parameters, 1):.2f} % within 3 std ({sum(r['seconds'] for r in results):.0f} s)"
    )
    # Sharpness is per scenario only: pooled over scenarios, one parameter's errors would mix nuisances.
    print(summary_line("pooled", pooled.two_sided, sharpness=False))


if __name__ == "__main__":
    main()
