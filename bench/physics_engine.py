"""Issue 19: `bsp identify` on a MuJoCo arm it did not write; counts valid-and-wrong and invalid-and-right.

Usage: ``python bench/physics_engine.py [--seeds 10] [--duration 120] [--wrench-hz 1000] [--quick] [--plan FILE]
[--only 0.12/springs/fixed] [--json OUT]`` (with the worktree first on PYTHONPATH).

Each scenario is a paper-protocol session (the sines of ``human_arm_cell()``, shoulder peak 0.03 rad/s, or the
same sines with periods / 4: 0.12 rad/s; ``--plan FILE`` adds a ``bsp plan`` trajectory) of a MuJoCo arm
(``test/physics/mujoco_cell.py``) with or without joint springs (0.30/0.50/0.15 Nm/rad x U(0.8, 1.2)), the
sensor fixed in world (``/tf_static``) or turning with the handle (per-sample ``/tf``). A seed draws the subject
(de Leva prior), its inertias, its friction and the sensor and marker noise. The bag goes through
``bsp identify BAG --json OUT`` (the CLI's own ``main``, in process) with the default model and again with
every ``--passive MODEL`` its findings name (and every ``--also-passive MODEL``). Every data-sourced
parameter (``source`` "data" or "data+prior") is scored against truth.json: |z| = |value - truth| / std. Per
scenario and model: runs, valid, valid-and-wrong (valid, some |z| > 3), invalid-and-right (invalid, every
|z| <= 3), the worst |z| and its parameter, two-sided calibration over the data-sourced parameters of its valid
runs (``bench/calibration.py``: z RMS with z = (value - truth) / std, 1 for an honest std; the shares within 1 and 2
std, 68 % and 95 % for an honest std), the sharpness (per parameter the median std over the RMS error across the
valid runs, 1 ideal; per kind, static moments "SM", Coulomb amplitudes "C", masses "m", the median and range over
its parameters), the most common cause of invalid (the first invalid finding's code and where), and the engine's
inertial / gravity torque per joint (RMS over RMS, peak over peak). Each seed draws its own arm unless
``--arm-seed`` fixes one (the seeds then vary the noise only): the sharpness is meant over one arm, and over arms
drawn per seed it mixes their errors.

How it was run for the issue-19 report (the estimator of main at 3f2534c, 2 shared cores, 1078 s):
``bsp plan --shoulder 0 1.2 --shoulder-range -70 -10 --elbow-range 10 100 --wrist-range -20 20 --duration 120
--json plan.json`` then ``python bench/physics_engine.py --seeds 8 --plan plan.json`` (120 s, wrench 1 kHz,
markers 100 Hz). Every default-model run was invalid except the planned trajectory without springs (8 valid,
6 of them beyond 3 std, worst |z| 5.1 on the upper-arm static moment); every run of the suggested
``coulomb+offset+stiffness`` model was valid and beyond 3 std (worst |z| 17 at 0.03 rad/s, 131 at 0.12 rad/s):
the engine's inertial torques (RMS 0.03 % of gravity at 0.03 rad/s, 0.5 % at 0.12 rad/s), which a sine makes
proportional to the angle, are taken up by the offset and stiffness columns, which are nearly collinear with
gravity (``--explain`` sets each static-moment error beside the shift inertia alone causes). Turning-sensor runs
were all invalid ("the model does not fit"). The same command with ``--seeds 2`` on main at 6427e3a (estimator with
inertia, per-sample rotations): no run valid-and-wrong; the springs rows invalid (elastic warning; the elastic model
"poor excitation", right), the planned trajectory with springs invalid ("does not fit") with no ``--passive``
suggestion although ``coulomb+offset+stiffness`` is valid and within 1.5 std there.
``--quick``: 2 seeds of 40 s at 250 Hz, 0.03 rad/s, fixed sensor.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
import tempfile
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import calibration
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "test" / "physics"))

from finding_kinds import cause_of, passive_options
from in_process import identify
from mujoco_bag import record, write_bag
from mujoco_cell import CellOptions, EngineRun, draw_arm, paper_sine
from scoring import Counts

from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.model import gravity_regressor
from bsp_ros.core.planning import planned_trajectory_from_file


@dataclass(frozen=True)
class Scenario:
    """One row group: trajectory, springs, sensor."""

    motion: str  # "0.03", "0.12" (paper sine peak rad/s) or "plan"
    springs: bool
    sensor: str

    @property
    def key(self) -> str:
        """``0.03/springs/fixed``: what ``--only`` matches."""
        return f"{self.motion}/{'springs' if self.springs else 'none'}/{self.sensor}"

    @property
    def name(self) -> str:
        return f"{self.motion:>4} {'springs' if self.springs else 'none':7} {self.sensor:7}"


@dataclass(kw_only=True)
class Tally(Counts):
    """The runs of one scenario and passive model: :class:`scoring.Counts`, the invalid runs' reasons and the
    failed runs' exit codes."""

    # An invalid estimate without a scored parameter counts as invalid-and-right here (every |z| <= 3 holds).
    UNSCORED_INVALID_RIGHT = True

    messages: collections.Counter[str] = field(default_factory=collections.Counter)
    failures: collections.Counter[str] = field(default_factory=collections.Counter)


def inertia_only_shift(run: EngineRun, passive: str) -> np.ndarray:
    """(3,) static-moment shift (kg m) the engine's inertial torques alone cause in a quasi-static fit.

    The inertial joint torques (MuJoCo's RNE) are regressed, all joints stacked and unweighted, on the estimator's
    columns: the gravity regressor of the grouped static moments and the ``passive`` model's columns per joint.
    Unbounded: where the estimator holds a stiffness at its bound 0, its shift differs.
    """
    _, inertial = run.torque_split_nm(every=4)
    q, velocity = run.q_rad[::4], run.qdot_rad_s[::4]
    terms = PassiveModel.parse("coulomb" if passive == "default" else passive)
    regressor = gravity_regressor(q)
    blocks = []
    for i in range(3):
        row = np.zeros((q.shape[0], 3 * len(terms.terms)))
        row[:, i * len(terms.terms) : (i + 1) * len(terms.terms)] = terms.columns(q, velocity, i)
        blocks.append(np.hstack((regressor[:, i, :], row)))
    solution = np.linalg.lstsq(np.vstack(blocks), inertial.T.reshape(-1), rcond=None)[0]
    return np.asarray(solution[:3])


def _trajectory(motion: str, plan: Path | None) -> Any:
    if motion == "plan":
        assert plan is not None
        return planned_trajectory_from_file(plan)
    return paper_sine(float(motion))


def run_scenario(
    scenario: Scenario, seeds: list[int], args: argparse.Namespace, workdir: Path, tallies: dict[str, Tally]
) -> dict[str, list[float]]:
    """Simulate and identify ``scenario`` for each seed; add to ``tallies`` (keyed by scenario and model)."""
    ratios: dict[str, list[float]] = collections.defaultdict(list)
    for seed in seeds:
        arm = draw_arm(seed if args.arm_seed is None else args.arm_seed, springs=scenario.springs)
        options = CellOptions(
            trajectory=_trajectory(scenario.motion, args.plan),
            duration_s=args.duration,
            wrench_hz=args.wrench_hz,
            sensor=scenario.sensor,
            seed=seed,
        )
        cell = record(arm, options)
        for kind, per_joint in cell.truth["simulation"]["inertial_to_gravity"].items():
            for joint, ratio in per_joint.items():
                ratios[f"{joint}_{kind}"].append(ratio)
        ratios["weld_drift_m"].append(cell.truth["simulation"]["weld_drift_max_m"])
        stem = f"{scenario.motion}_{int(scenario.springs)}_{scenario.sensor}_{seed}"
        bag = write_bag(workdir / stem, cell)
        code, estimate = identify(bag, workdir / f"{stem}_default.json")
        models = [("default", code, estimate)]
        for model in sorted(set(passive_options(estimate.get("quality", {}))) | set(args.also_passive)):
            code_m, estimate_m = identify(bag, workdir / f"{stem}_{model}.json", "--passive", model)
            models.append((model, code_m, estimate_m))
        for model, code_m, estimate_m in models:
            tally = tallies.setdefault(f"{scenario.name} {model}", Tally())
            if not estimate_m:
                tally.count_failure()
                tally.failures[f"exit {code_m}"] += 1
                continue
            run = tally.score(estimate_m, cell.truth)
            if not run.valid:
                tally.messages[cause_of(estimate_m.get("quality", {}))] += 1
            if args.verbose:
                top = ", ".join(f"{k} {v:.1f}" for k, v in sorted(run.z.items(), key=lambda kv: -kv[1])[:3])
                print(f"  seed {seed} {model}: valid={run.valid} {top}", flush=True)
            if args.explain:
                shift = inertia_only_shift(cell.run, model)
                rows = []
                for j, segment in enumerate(("upper_arm", "forearm", "hand")):
                    q = estimate_m["segments"][segment]["static_moment_kgm"]
                    error = q["value"] - cell.truth["segments"][segment]["static_moment_kgm"]
                    rows.append(f"{segment} {error:+.2e} (inertia alone {shift[j]:+.2e}, std {q['std']:.1e})")
                print(f"  seed {seed} {model}: static moment error " + "; ".join(rows), flush=True)
    return ratios


def _row(name: str, t: Tally) -> str:
    """One table row: a scenario and passive model's runs and error rates."""
    common = t.messages.most_common(1)
    reason = f"{common[0][1]}x {common[0][0]}" if common else "-"
    fail = f" failed {dict(t.failures)}" if t.failures else ""
    two_sided = (
        f"{calibration.calibration_columns(t.two_sided.calibration())}"
        f" {calibration.sharpness_columns(t.two_sided.sharpness())}"
    )
    return (
        f"{name:52} {t.runs:4} {t.valid:5} {t.valid_wrong:7} {t.invalid_right:9} {two_sided}  {t.worst_z:8.3g} "
        f"({t.worst_param})  {reason}{fail}"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--first-seed", type=int, default=0, help="seeds FIRST .. FIRST + SEEDS - 1 (split a long run)")
    parser.add_argument("--duration", type=float, default=120.0)
    parser.add_argument("--wrench-hz", type=float, default=1000.0)
    parser.add_argument("--plan", type=Path, help="a `bsp plan --json` file: adds the planned-trajectory rows")
    parser.add_argument(
        "--also-passive", action="append", default=[], metavar="MODEL", help="try this --passive model on every run too"
    )
    parser.add_argument(
        "--arm-seed",
        type=int,
        help="draw every run's arm from this seed (one arm; the seeds vary the noise only), for the sharpness",
    )
    parser.add_argument("--only", default="", help="only scenarios whose key (e.g. 0.03/none/fixed) contains this")
    parser.add_argument("--quick", action="store_true", help="2 seeds of 40 s at 250 Hz, 0.03 rad/s fixed sensor")
    parser.add_argument("--json", type=Path, help="write the table as JSON here")
    parser.add_argument("--verbose", action="store_true", help="the worst three |z| of every run")
    parser.add_argument(
        "--explain", action="store_true", help="per run: static-moment errors beside the shift inertia alone causes"
    )
    args = parser.parse_args(argv)
    if args.quick:
        args.seeds, args.duration, args.wrench_hz = min(args.seeds, 2), 40.0, 250.0
    motions = ["0.03"] if args.quick else ["0.03", "0.12"]
    if args.plan is not None:
        motions.append("plan")
    sensors = ["fixed"] if args.quick else ["fixed", "turning"]
    scenarios = [Scenario(m, s, sensor) for m in motions for s in (False, True) for sensor in sensors]
    scenarios = [s for s in scenarios if args.only in s.key]
    tallies: dict[str, Tally] = {}
    engine: dict[str, dict[str, float]] = {}
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="physics_engine_") as tmp:
        for scenario in scenarios:
            print(f"{scenario.name} ...", flush=True)
            seeds = list(range(args.first_seed, args.first_seed + args.seeds))
            before = set(tallies)
            ratios = run_scenario(scenario, seeds, args, Path(tmp), tallies)
            engine[scenario.name] = {k: max(v) for k, v in ratios.items()}
            for name in [n for n in tallies if n not in before]:  # as it finishes: a long run is read as it goes
                print("  " + _row(name, tallies[name]), flush=True)
    print(f"\n{args.seeds} seeds, {args.duration:g} s, wrench {args.wrench_hz:g} Hz, {time.monotonic() - start:.0f} s")
    header = (
        f"{'motion sens sensor  model':52} runs valid v&wrong inv&right {calibration.calibration_header()}"
        f" {calibration.sharpness_header()}  worst|z| (parameter)   most common invalid"
    )
    arms = "one arm" if args.arm_seed is not None else "an arm drawn per seed: the sharpness mixes arms"
    print(f"sharpness over the valid runs of a row ({arms}); calibration over their data-sourced parameters")
    print(header)
    for name, t in tallies.items():
        print(_row(name, t))
    print("\nengine, largest over seeds: inertial / gravity torque per joint (RMS, peak), weld drift (m)")
    for name, values in engine.items():
        print(f"{name}  " + "  ".join(f"{k} {v:.3g}" for k, v in values.items()))
    if args.json:
        args.json.write_text(
            json.dumps(
                {
                    "tallies": {
                        k: {
                            **t.counts_json(),
                            "worst_z": t.worst_z,
                            "worst_param": t.worst_param,
                            "calibration": asdict(t.two_sided.calibration()),
                            "sharpness": {k: asdict(v) for k, v in t.two_sided.sharpness().items()},
                            "messages": dict(t.messages),
                        }
                        for k, t in tallies.items()
                    },
                    "engine": engine,
                },
                indent=1,
            )
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
