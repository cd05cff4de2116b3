"""Issue 20: one arm recorded upright and with the trunk tilted, in MuJoCo; `bsp identify` on one and on both.

Usage: ``python bench/two_postures.py [--seeds 5] [--tilt-deg 25] [--duration 60] [--speeds 0.03 0.12] [--json OUT]``
(with the worktree first on PYTHONPATH).

Per seed a MuJoCo arm (``test/physics/mujoco_cell.py``: de Leva subject, joint springs 0.30/0.50/0.15 Nm/rad
x U(0.8, 1.2) about the trunk, dry friction, its own F/T sensor fixed in world) follows the paper's sines
(``human_arm_cell()``, shoulder peak 0.03 rad/s, or periods / 4: 0.12 rad/s) twice: upright, then with the
trunk turned by ``--tilt-deg`` and the robot moving the arm through the same angles relative to it. Each
recording is a bag (250 Hz wrench, 100 Hz markers); ``bsp identify`` (the CLI's ``main``, in process) runs on
the upright bag alone and on both with ``--trunk-tilt-deg 0 TILT``, with the default model and with
``--passive coulomb+offset+stiffness``. Every data-sourced parameter is scored against truth.json
(``bench/scoring.py``). Per speed, recordings and model: runs, valid, valid-and-wrong (some |z| > 3),
invalid-and-right (every |z| <= 3), the worst |z| and its parameter, the median relative std of each
static moment and the most common cause of the invalid runs (the first invalid finding's code and where,
``bench/finding_kinds.py``; "(no estimate)" where ``bsp identify`` wrote none).
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import io
import json
import math
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "test" / "physics"))

from finding_kinds import cause_of
from mujoco_bag import record, write_bag
from mujoco_cell import CellOptions, draw_arm, paper_sine
from scoring import rates, verdict, z_scores

from bsp_ros.cli import main as bsp_main

MODELS = ("default", "coulomb+offset+stiffness")
SEGMENTS = ("upper_arm", "forearm", "hand")
START_NS = 1_700_000_000_000_000_000
NO_ESTIMATE = "(no estimate)"


def identify(bags: list[Path], tilts_deg: list[float], model: str, out: Path) -> dict[str, Any]:
    """``bsp identify BAG... [--trunk-tilt-deg ...] [--passive MODEL] --json OUT`` in process: the estimate."""
    argv = ["identify", *map(str, bags), "--json", str(out), "--format", "none"]
    if len(bags) > 1:
        argv += ["--trunk-tilt-deg", *(f"{t:g}" for t in tilts_deg)]
    if model != "default":
        argv += ["--passive", model]
    out.unlink(missing_ok=True)
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        bsp_main(argv)
    return json.loads(out.read_text()) if out.exists() else {"quality": {"valid": False}}


def _cause(document: dict[str, Any]) -> str:
    """Why a run is invalid: its first invalid finding's code and where, or "(no estimate)" where none was written."""
    return cause_of(document["quality"]) if "schema" in document else NO_ESTIMATE


def _common_cause(runs: list[dict[str, Any]]) -> str:
    """The most common cause of the invalid runs, with its count; '-' when all are valid."""
    causes = collections.Counter(r["cause"] for r in runs if not r["valid"])
    if not causes:
        return "-"
    cause, count = causes.most_common(1)[0]
    return f"{cause} ({count})"


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark and print its table."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--tilt-deg", type=float, default=25.0)
    parser.add_argument("--duration", type=float, default=60.0, help="each recording, s")
    parser.add_argument("--speeds", type=float, nargs="+", default=[0.03, 0.12], help="shoulder peak speed, rad/s")
    parser.add_argument("--json", type=Path, help="write every run's scores here")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    rows: dict[tuple[float, str, str], list[dict[str, Any]]] = collections.defaultdict(list)
    with tempfile.TemporaryDirectory() as where:
        tmp = Path(where)
        for speed in args.speeds:
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                arm = draw_arm(seed, springs=True)
                bags = []
                for k, tilt in enumerate((0.0, args.tilt_deg)):
                    options = CellOptions(
                        trajectory=paper_sine(speed),
                        duration_s=args.duration,
                        wrench_hz=250.0,
                        seed=100 * seed + k,
                        trunk_tilt_rad=math.radians(tilt),
                        start_ns=START_NS + k * 600_000_000_000,
                    )
                    bags.append(write_bag(tmp / f"s{seed}_{speed:g}_{k}", record(arm, options)))
                truth = json.loads((bags[0] / "truth.json").read_text())
                for label, chosen in (("upright", bags[:1]), ("both", bags)):
                    for model in MODELS:
                        document = identify(chosen, [0.0, args.tilt_deg], model, tmp / "estimate.json")
                        z = z_scores(document, truth)
                        worst = max(z.items(), key=lambda kv: kv[1]) if z else ("-", math.nan)
                        relative = {
                            s: document["segments"][s]["static_moment_kgm"]["std"]
                            / truth["segments"][s]["static_moment_kgm"]
                            for s in SEGMENTS
                            if "segments" in document
                        }
                        valid = bool(document["quality"]["valid"])
                        rows[(speed, label, model)].append(
                            {
                                "seed": seed,
                                "valid": valid,
                                "worst": worst,
                                "verdict": verdict(valid, worst[1]),
                                "relative_std": relative,
                                "cause": _cause(document) if not valid else "",
                                "message": document["quality"].get("message", ""),
                            }
                        )
            print(f"  {speed:g} rad/s: {args.seeds} seeds, {time.perf_counter() - started:.0f} s", flush=True)
    print(
        f"MuJoCo arm with springs, paper sines, {args.duration:g} s per recording, trunk tilt {args.tilt_deg:g} deg, "
        f"seeds {args.first_seed}-{args.first_seed + args.seeds - 1}"
    )
    header = (
        f"{'speed':>6s} {'recordings':10s} {'model':26s} {'runs':>4s} {'valid':>5s} {'v&wrong':>7s} {'inv&right':>9s}"
    )
    print(header + f"  {'worst|z| (parameter)':34s} median std % (upper arm, forearm, hand)  most common invalid")
    totals = [0, 0, 0]
    for (speed, label, model), runs in rows.items():
        n, wrong, right = rates(r["verdict"] for r in runs)
        totals = [totals[0] + n, totals[1] + wrong, totals[2] + right]
        n_valid = sum(r["valid"] for r in runs)
        worst = max(runs, key=lambda r: r["worst"][1] if not math.isnan(r["worst"][1]) else -1.0)["worst"]
        medians = [np.median([r["relative_std"][s] for r in runs if s in r["relative_std"]]) * 100 for s in SEGMENTS]
        print(
            f"{speed:6g} {label:10s} {model:26s} {n:4d} {n_valid:5d} {wrong:7d} {right:9d}  "
            f"{worst[1]:5.2f} ({worst[0]})".ljust(105)
            + "  "
            + ", ".join(f"{m:.3g}" for m in medians).ljust(22)
            + _common_cause(runs)
        )
    elapsed = time.perf_counter() - started
    print(f"valid-and-wrong {totals[1]}/{totals[0]}, invalid-and-right {totals[2]}/{totals[0]} ({elapsed:.0f} s)")
    if args.json:
        args.json.write_text(json.dumps({f"{k[0]}/{k[1]}/{k[2]}": v for k, v in rows.items()}, indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
