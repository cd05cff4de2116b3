"""Issue 19: segment inertias from a faster protocol (two sines per joint within a peak speed), our simulator.

Usage: ``python bench/inertia_excitation.py [--seeds 5] [--speed 0.15] [--duration 120] [--mujoco] [--json OUT]``
(with the worktree first on PYTHONPATH).

Per seed a 3-segment human arm (``human_arm_cell``: de Leva male 75 kg 1.78 m, rigid-body dynamics, Coulomb
friction) follows ``MultiSineTrajectory.within_speed`` (periods 2.1/7.9, 2.7/9.3, 3.3/11.1 s, each joint's peak
speed ``--speed``) and, for comparison, the paper's single sines sped up to the same shoulder peak speed. Each
session is identified (``identify_session``) three ways: exact (markers on the joint centres and a tared sensor:
placement sd 0, zero sd 0), robot (the robot's handle pose for the contact point, 0.5 mm, tared) and default
(2 mm skin placement, untared 1 N zero). Per protocol and way: runs, valid, valid-and-wrong, invalid-and-right
(``bench/scoring.py``), and per segment the median |error| and median std of the grouped inertia and of the
inertia about the proximal joint (``inertia_kgm2``), in % of the truth, with the share of runs in which it came
from the data (``source`` data). ``--mujoco`` adds the two-sine protocol on the MuJoCo arm
(``test/physics/mujoco_cell.py``: its own inertias, friction and F/T sensor; 60 s, 250 Hz), through ``bsp identify``
tared (``--zero-sd-n 0 --zero-sd-nm 0``) and with the defaults.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import statistics
import sys
import time
from typing import Any

from scoring import rates, verdict, z_scores

from bsp_ros.core import simulation as sim
from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.pipeline import IdentifyOptions, identify_session

PERIODS_S = ((2.1, 7.9), (2.7, 9.3), (3.3, 11.1))
PHASES_RAD = ((0.0, 1.3), (1.0, 2.9), (2.0, 0.4))
SEGMENTS = ("upper_arm", "forearm", "hand")
WAYS = {
    "exact": {"marker_placement_sd_m": 0.0, "zero_sd_n": 0.0, "zero_sd_nm": 0.0},
    "robot": {"zero_sd_n": 0.0, "zero_sd_nm": 0.0},
    "default": {},
}
KEYS = ("grouped_inertia_kgm2", "inertia_kgm2")


def _spec(protocol: str, speed: float, duration: float, seed: int) -> sim.CellSpec:
    base = sim.human_arm_cell(duration_s=duration, seed=seed)
    if protocol == "two sines":
        motion: Any = sim.MultiSineTrajectory.within_speed((-43.3, 45.0, 0.2), PERIODS_S, speed, PHASES_RAD)
    else:
        slow = base.trajectory
        assert isinstance(slow, sim.TrajectorySpec)
        motion = slow.speed_scaled(speed / slow.peak_speed_rad_s[0])
    return dataclasses.replace(base, trajectory=motion)


def _engine_runs(seeds: int, speed: float, duration: float) -> list[dict[str, Any]]:
    """The two-sine protocol on the MuJoCo arm (``test/physics/mujoco_cell.py``), through ``bsp identify``."""
    import contextlib
    import io
    import tempfile
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "test" / "physics"))
    from mujoco_bag import record, write_bag
    from mujoco_cell import CellOptions, draw_arm

    from bsp_ros.cli import main as bsp

    out = []
    motion = sim.MultiSineTrajectory.within_speed((-43.3, 45.0, 0.2), PERIODS_S, speed, PHASES_RAD)
    for seed in range(seeds):
        options = CellOptions(trajectory=motion, duration_s=duration, wrench_hz=250.0, seed=seed)
        with tempfile.TemporaryDirectory() as folder:
            bag = write_bag(Path(folder) / "session", record(draw_arm(seed), options))
            truth = json.loads((bag / "truth.json").read_text())
            for way, extra in (("tared", ["--zero-sd-n", "0", "--zero-sd-nm", "0"]), ("default", [])):
                with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
                    bsp(["identify", str(bag), "--json", f"{folder}/e.json", "--format", "none", *extra])
                document = json.loads(Path(f"{folder}/e.json").read_text())
                out.append(_scored("two sines (MuJoCo)", way, seed, document, truth))
                print(f"  MuJoCo seed {seed} {way}: valid {out[-1]['valid']}", file=sys.stderr)
    return out


def _scored(protocol: str, way: str, seed: int, document: dict[str, Any], truth: dict[str, Any]) -> dict[str, Any]:
    z = max(z_scores(document, truth).values(), default=float("nan"))
    run: dict[str, Any] = {
        "protocol": protocol,
        "way": way,
        "seed": seed,
        "valid": bool(document["quality"]["valid"]),
        "max_z": z,
        "verdict": verdict(bool(document["quality"]["valid"]), z),
        "message": document["quality"].get("message", ""),
    }
    for segment in SEGMENTS:
        for key in KEYS:
            q, true = document["segments"][segment].get(key), truth["segments"][segment].get(key)
            if q is None or true is None or q.get("value") is None:
                continue
            run[f"{segment}/{key}"] = {
                "err_pct": 100.0 * (q["value"] - true) / true,
                "std_pct": 100.0 * q["std"] / true,
                "data": q["source"] == "data",
            }
    return run


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--speed", type=float, default=0.15, help="peak joint speed, rad/s (default 0.15)")
    parser.add_argument("--duration", type=float, default=120.0)
    parser.add_argument("--json", metavar="OUT")
    parser.add_argument("--mujoco", action="store_true", help="also the two sines on the MuJoCo arm (60 s, 250 Hz)")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    runs: list[dict[str, Any]] = []
    for protocol in ("two sines", "one sine"):
        for seed in range(args.seeds):
            base = _spec(protocol, args.speed, args.duration, seed)
            for way, changes in WAYS.items():
                spec = dataclasses.replace(base, robot_handle_pose=way == "robot")
                simulated = sim.simulate_cell(spec)
                truth = simulated.truth.to_dict()
                options = IdentifyOptions(subject=SubjectInfo(75.0, 1.78, "male"), **changes)
                document = identify_session(simulated.session, options)
                run = _scored(protocol, way, seed, document, truth)
                runs.append(run)
                print(
                    f"  {protocol} seed {seed} {way}: valid {run['valid']}, max|z| {run['max_z']:.2f}", file=sys.stderr
                )
    if args.mujoco:
        runs += _engine_runs(args.seeds, args.speed, 60.0)
    print(f"human arm, {args.duration:g} s, peak {args.speed:g} rad/s, {args.seeds} seeds; inertia |error| / std")
    print("(median over seeds, % of the truth; 'data' = share of runs identified from the data)")
    header = f"{'protocol':18} {'way':8} runs valid v&wrong inv&right  " + "  ".join(f"{s:>24}" for s in SEGMENTS)
    for key in KEYS:
        print(f"\n{key}\n{header}")
        for protocol, way in dict.fromkeys((r["protocol"], r["way"]) for r in runs):
            rows = [r for r in runs if r["protocol"] == protocol and r["way"] == way]
            n, wrong, thrown = rates(r["verdict"] for r in rows)
            cells = []
            for segment in SEGMENTS:
                found = [r[f"{segment}/{key}"] for r in rows if f"{segment}/{key}" in r]
                if not found:
                    cells.append(f"{'-':>24}")
                    continue
                err = statistics.median(abs(f["err_pct"]) for f in found)
                std = statistics.median(f["std_pct"] for f in found)
                data = sum(f["data"] for f in found) / len(found)
                cells.append(f"{err:6.2f} / {std:6.2f} data {data:4.0%}")
            valid = sum(r["valid"] for r in rows)
            print(f"{protocol:18} {way:8} {n:4} {valid:5} {wrong:7} {thrown:9}  " + "  ".join(cells))
    total, wrong, thrown = rates(r["verdict"] for r in runs)
    print(
        f"\nvalid-and-wrong {wrong}/{total}, invalid-and-right {thrown}/{total} ({time.perf_counter() - started:.0f} s)"
    )
    if args.json:
        with open(args.json, "w", encoding="utf-8") as stream:
            json.dump(runs, stream, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
