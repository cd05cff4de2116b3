"""Honest and sharp on a physics engine: one MuJoCo arm, markers re-placed every session, a tared sensor.

Usage: ``python bench/engine_sharpness.py [--arms 0 1] [--sessions 8] [--protocols paper fast plan mechanical]
[--sd-mm 2] [--duration 120] [--wrench-hz 1000] [--json OUT] [--brute]`` (with the worktree first on PYTHONPATH).

Per protocol and arm, the MuJoCo cell (``test/physics/mujoco_cell.py``) runs once; every session then re-places
the markers (each marker's (along, normal) offset from its joint centre drawn at ``--sd-mm`` per in-plane axis, the
same sd the estimator assumes, ``--marker-placement-sd-mm``) and draws its own sensor and marker noise, and goes
through ``bsp identify BAG --zero-sd-n 0 --zero-sd-nm 0`` (a tared sensor: the engine's sensor has no zero
offset). The arm's physics does not depend on where the skin markers sit (massless sites), so one engine run per
arm serves its sessions: the markers are moved by the planar kinematics of the engine's own joint angles.

Protocols: ``paper`` (the paper's sines of ``human_arm_cell()``, shoulder peak 0.03 rad/s), ``fast`` (the same sines
four times faster), ``plan`` (a ``bsp plan`` trajectory: ``--plan FILE``, else one within the ranges of
``bench/in_process.py`` as long as the session), ``mechanical`` (the paper's 2-segment mechanical arm of
``test/physics/mujoco_mechanical.py`` on its sines; arm 0 the nominal arm, others a seeded manufacturing spread;
scored on the quantities from the data alone, as the masses and centres of mass ``bsp identify`` fuses with the human
anthropometric table do not describe a machine).

Printed per protocol and arm, and pooled per protocol: sessions, valid, valid-and-wrong, invalid-and-right, the
two-sided calibration of the valid sessions (z RMS, within 1 and 2 std; ``bench/calibration.py``) and the
sharpness of every static moment and Coulomb amplitude (median std over the RMS error across the sessions; 1
ideal, an honest std's falls in about 0.7-1.4 over 8 sessions). ``--sd-mm 0`` keeps the markers on the joint
centres: then the inflation column gives each static moment's and Coulomb amplitude's std over what the assumed
placement and the sensor noise alone give (the ``marker_placement`` and ``sensor_noise`` terms of its budget; 1
means no inflation). ``--brute`` instead checks the placement term against brute force per arm (each marker moved
a tenth of ``--sd-mm`` alone, ``--brute-step``) and says how far the row's ``--sessions`` drawn placements move each
parameter against average.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import tempfile
import time
from collections import defaultdict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import calibration
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "test" / "physics"))

from in_process import identify, planned_in_ranges
from mujoco_bag import record, write_bag
from mujoco_cell import CellOptions, EngineRun, draw_arm, paper_sine, run_engine
from mujoco_mechanical import mechanical_arm, mechanical_sine
from scoring import Counts, z_scores

from bsp_ros.core.planning import planned_trajectory_from_file

PROTOCOLS = ("paper", "fast", "plan", "mechanical")
# Quantities whose sharpness the acceptance reads, and the most an honest std's median over the RMS error may be.
SHARP_KINDS = {"static_moment_kgm": "static moments", "coulomb_nm": "Coulomb amplitudes"}
SHARPNESS_LIMIT = 1.5


@dataclasses.dataclass(kw_only=True)
class Row(Counts):
    """The sessions of one protocol and arm: :class:`scoring.Counts` and why estimates were invalid, each static
    moment's and Coulomb amplitude's std inflation and the placement scales."""

    reasons: dict[str, int] = dataclasses.field(default_factory=lambda: defaultdict(int))
    inflation: dict[str, list[float]] = dataclasses.field(default_factory=lambda: defaultdict(list))
    scales: list[float] = dataclasses.field(default_factory=list)


def markers_replaced(run: EngineRun, offsets_m: np.ndarray) -> np.ndarray:
    """(N, K, 3) the engine's marker trajectories with marker k moved by ``offsets_m[k]`` = (along, normal), m,
    in the frame of the segment it sits on (the hand marker, the last, on the last segment)."""
    n_segments = run.q_rad.shape[1]
    phi = np.cumsum(run.q_rad, axis=1) + run.trunk_tilt_rad
    moved = run.markers_m.copy()
    for k, (along, normal) in enumerate(offsets_m):
        angle = phi[:, min(k, n_segments - 1)]
        c, s = np.cos(angle), np.sin(angle)
        moved[:, k, 1] += along * c - normal * s
        moved[:, k, 2] += along * s + normal * c
    return moved


def _trajectory(protocol: str, plan: Path) -> Any:
    if protocol == "paper":
        return paper_sine(0.03)
    if protocol == "fast":
        return paper_sine(0.12)
    if protocol == "plan":
        return planned_trajectory_from_file(plan)
    return mechanical_sine()


def _arm(protocol: str, arm_seed: int) -> Any:
    if protocol == "mechanical":
        return mechanical_arm(None if arm_seed == 0 else arm_seed)
    return draw_arm(arm_seed)


def _inflation(estimate: dict[str, Any], row: Row) -> None:
    """Each static moment's and Coulomb amplitude's std over its placement-and-noise-only std."""
    for group in ("segments", "joints"):
        for owner, quantities in estimate.get(group, {}).items():
            for key in SHARP_KINDS:
                q = quantities.get(key)
                if not isinstance(q, dict) or not q.get("budget"):
                    continue
                budget = q["budget"]
                alone = math.hypot(budget.get("marker_placement", 0.0), budget.get("sensor_noise", 0.0))
                if alone > 0:
                    row.inflation[f"{key}/{owner}"].append(float(q["std"]) / alone)


def _fused(quantity: Any) -> bool:
    return isinstance(quantity, dict) and quantity.get("source") == "data+prior"


def data_only(estimate: dict[str, Any]) -> dict[str, Any]:
    """The estimate with its data+prior quantities left out: on a machine, a human table's prior is not its own."""
    out = dict(estimate)
    for group in ("segments", "joints"):
        out[group] = {
            owner: {k: q for k, q in quantities.items() if not _fused(q)}
            for owner, quantities in estimate.get(group, {}).items()
        }
    return out


def score(row: Row, code: int, estimate: dict[str, Any], truth: dict[str, Any]) -> None:
    """Add one session's estimate to ``row``."""
    if not estimate:
        row.count_failure()
        row.reasons[f"exit {code}"] += 1
        return
    if len(truth["segments"]) == 2:
        estimate = data_only(estimate)
    row.scales.append(float(estimate["quality"].get("marker_placement", {}).get("scale_from_data", math.nan)))
    if not row.score(estimate, truth).valid:
        codes = [f["code"] for f in estimate["quality"].get("findings", []) if f.get("severity") == "invalid"]
        row.reasons[",".join(codes) or "?"] += 1
    _inflation(estimate, row)


def _engine(protocol: str, arm_seed: int, args: argparse.Namespace) -> tuple[Any, CellOptions, EngineRun]:
    """The arm of ``protocol`` and ``arm_seed``, its cell options, and its one engine run."""
    arm = _arm(protocol, arm_seed)
    options = CellOptions(
        trajectory=_trajectory(protocol, args.plan), duration_s=args.duration, wrench_hz=args.wrench_hz
    )
    return arm, options, run_engine(arm, options)


def drawn_offsets_m(arm_seed: int, session: int, n_markers: int, sd_mm: float) -> np.ndarray:
    """(K, 2) the (along, normal) offsets session ``session`` of arm ``arm_seed`` re-places its markers by, m."""
    rng = np.random.default_rng([arm_seed, session, 50])
    return rng.normal(0.0, sd_mm * 1e-3, (n_markers, 2))


def _session(
    engine: tuple[Any, CellOptions, EngineRun], offsets_m: np.ndarray, seed: int, stem: Path, args: argparse.Namespace
) -> tuple[int, dict[str, Any], dict[str, Any]]:
    """Identify one session of the engine run with the markers moved by ``offsets_m`` and noise ``seed``: the exit
    code, the estimate document and the truth."""
    arm, options, run = engine
    moved = dataclasses.replace(run, markers_m=markers_replaced(run, offsets_m))
    session_options = dataclasses.replace(options, seed=seed, skin_offset_m=tuple(map(tuple, offsets_m)))
    cell = record(arm, session_options, moved)
    bag = write_bag(stem, cell)
    extra = ["--zero-sd-n", "0", "--zero-sd-nm", "0", "--marker-placement-sd-mm", str(args.assumed_sd_mm)]
    code, estimate = identify(bag, stem.with_suffix(".json"), *extra, *args.identify)
    return code, estimate, cell.truth


def run_arm(protocol: str, arm_seed: int, args: argparse.Namespace, workdir: Path) -> Row:
    """Simulate one arm on ``protocol`` once and identify ``args.sessions`` sessions with re-placed markers."""
    engine = _engine(protocol, arm_seed, args)
    n_markers = engine[2].markers_m.shape[1]
    row = Row()
    for session in range(args.sessions):
        offsets = drawn_offsets_m(arm_seed, session, n_markers, args.sd_mm)
        stem = f"{protocol}_{arm_seed}_{session}"
        code, estimate, truth = _session(engine, offsets, 1000 * arm_seed + session, workdir / stem, args)
        score(row, code, estimate, truth)
        if args.verbose:
            z = z_scores(estimate, truth) if estimate else {}
            top = sorted(z.items(), key=lambda kv: -kv[1])[:3]
            valid = estimate.get("quality", {}).get("valid") if estimate else None
            print(f"  {stem}: valid={valid} " + ", ".join(f"{k} {v:.2f}" for k, v in top), flush=True)
    return row


def _sharp_values(estimate: dict[str, Any]) -> dict[str, tuple[float, float]]:
    """Each static moment's and Coulomb amplitude's value and placement term, ``kind/owner``."""
    out = {}
    for group in ("segments", "joints"):
        for owner, quantities in estimate.get(group, {}).items():
            for key in SHARP_KINDS:
                q = quantities.get(key)
                if isinstance(q, dict) and q.get("value") is not None:
                    out[f"{key}/{owner}"] = (float(q["value"]), float(q.get("budget", {}).get("marker_placement", 0.0)))
    return out


def brute_force(protocol: str, arm_seed: int, args: argparse.Namespace, workdir: Path) -> None:
    """Print each static moment's and Coulomb amplitude's placement term against brute force: the exact-marker
    session and one per marker and axis moved alone by ``args.brute_step`` of ``args.sd_mm`` (the same noise), the
    change scaled to ``args.sd_mm``; and how far the row's drawn placements move it (the RMS over ``args.sessions``
    of their linear prediction, over brute force's: 1 on average, and an honest std's sharpness over those sessions
    about its inverse).

    The placement term is the exact-marker fit's linear response, at that fit's per-joint weights. A whole sd moved
    alone can change those weights several-fold (a 2 mm normal offset at the wrist left a residual of 5 times the
    sensor noise on the 4x faster sines, and the wrist's weight fell 30-fold), and the moved fit then responds at
    its own weights: the step is a tenth of an sd so that brute force measures the same derivative."""
    engine = _engine(protocol, arm_seed, args)
    n_markers = engine[2].markers_m.shape[1]
    seed = 1000 * arm_seed
    _, exact, _ = _session(engine, np.zeros((n_markers, 2)), seed, workdir / f"brute_{protocol}_{arm_seed}", args)
    base = _sharp_values(exact)
    response = {name: np.zeros(2 * n_markers) for name in base}
    for k in range(2 * n_markers):
        offsets = np.zeros(2 * n_markers)
        offsets[k] = args.brute_step * args.sd_mm * 1e-3
        stem = workdir / f"brute_{protocol}_{arm_seed}_{k}"
        _, moved, _ = _session(engine, offsets.reshape(n_markers, 2), seed, stem, args)
        for name, (value, _) in _sharp_values(moved).items():
            if name in response:
                response[name][k] = (value - base[name][0]) / args.brute_step
    draws = np.array([drawn_offsets_m(arm_seed, s, n_markers, args.sd_mm).ravel() for s in range(args.sessions)]) / (
        args.sd_mm * 1e-3
    )
    for name, per_offset in response.items():
        brute = float(np.linalg.norm(per_offset))
        drawn = float(np.sqrt(np.mean((draws @ per_offset) ** 2))) / brute if brute > 0 else math.nan
        term = base[name][1]
        print(
            f"  {protocol} arm {arm_seed} {name:32} placement term {term:.5f}  brute force {brute:.5f}  "
            f"ratio {term / brute:.2f}  drawn placements {drawn:.2f}",
            flush=True,
        )


def sharpness_of(row: Row) -> dict[str, float]:
    """Each static moment's and Coulomb amplitude's sharpness over the row's sessions (where it has two or more)."""
    out = {}
    for name, pairs in sorted(row.two_sided.samples.items()):
        if calibration.quantity(name) in SHARP_KINDS and len(pairs) >= 2:
            errors, stds = zip(*pairs, strict=True)
            out[name] = calibration.sharpness(errors, stds)
    return out


def _per_parameter(row: Row) -> str:
    """Each static moment's and Coulomb amplitude's sharpness, ``owner value``."""
    parts = []
    for name, value in sharpness_of(row).items():
        kind = "SM" if name.startswith("static") else "C"
        parts.append(f"{kind} {name.split('/')[1]} {value:.2f}")
    return ", ".join(parts)


def print_row(label: str, row: Row) -> None:
    """One line of counts and calibration, then the per-parameter sharpness (and inflation, if any)."""
    c = row.two_sided.calibration()
    reasons = ", ".join(f"{n}x {r}" for r, n in sorted(row.reasons.items(), key=lambda kv: -kv[1])) or "-"
    print(
        f"{label:22} {row.runs:4} {row.valid:5} {row.valid_wrong:7} {row.invalid_right:9} "
        f"{calibration.calibration_columns(c)} {row.worst_z:7.2f} ({row.worst_param})  invalid: {reasons}"
    )
    scales = np.array(row.scales)
    scales = scales[np.isfinite(scales)]  # an invalid estimate has no placement scale
    scale_text = f"placement scale median {np.median(scales):.2f}, max {scales.max():.2f}" if scales.size else "-"
    print(f"{'':22} sharpness: {_per_parameter(row)}; {scale_text}")
    if row.inflation:
        values = {k: float(np.median(v)) for k, v in sorted(row.inflation.items())}
        ratios = ", ".join(f"{k.split('/')[1]} {v:.2f}" for k, v in values.items())
        print(f"{'':22} std / (placement + noise): {ratios}")


def acceptance(rows: dict[str, Row]) -> list[str]:
    """The acceptance figures over every protocol's arms: share valid, z RMS, the widest sharpness."""
    total = Row()
    worst_sharp = (0.0, "")
    for label, row in rows.items():
        total.pool(row)
        for name, value in sharpness_of(row).items():
            if math.isfinite(value) and value > worst_sharp[0]:
                worst_sharp = (value, f"{label} {name}")
    c = total.two_sided.calibration()
    return [
        f"valid {total.valid}/{total.runs} ({100 * total.valid / max(total.runs, 1):.0f} %, at least 95 %)",
        f"valid-and-wrong {total.valid_wrong}",
        f"z RMS {c.z_rms:.3g} (0.7-1.3), within 1 std {100 * c.within_1:.0f} %, within 2 std {100 * c.within_2:.0f} %",
        f"widest static-moment / Coulomb sharpness {worst_sharp[0]:.2f} ({worst_sharp[1]}; at most {SHARPNESS_LIMIT})",
    ]


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arms", type=int, nargs="+", default=[0, 1], help="arm seeds (mechanical: 0 the nominal arm)")
    parser.add_argument("--sessions", type=int, default=8)
    parser.add_argument("--protocols", nargs="+", choices=PROTOCOLS, default=list(PROTOCOLS))
    parser.add_argument("--sd-mm", type=float, default=2.0, help="re-placement sd per in-plane axis, mm (0: exact)")
    parser.add_argument("--assumed-sd-mm", type=float, default=2.0, help="the placement sd identify assumes, mm")
    parser.add_argument("--duration", type=float, default=120.0)
    parser.add_argument("--wrench-hz", type=float, default=1000.0)
    parser.add_argument("--plan", type=Path, help="a `bsp plan --json` file (default: one within the benches' ranges)")
    parser.add_argument("--identify", nargs=argparse.REMAINDER, default=[], help="further `bsp identify` options")
    parser.add_argument("--json", type=Path, help="write the rows' counts and figures here")
    parser.add_argument("--verbose", action="store_true", help="every session's worst three |z|")
    parser.add_argument(
        "--brute", action="store_true", help="instead: the placement term against each marker moved alone"
    )
    parser.add_argument(
        "--brute-step", type=float, default=0.1, help="with --brute: each marker's step, a share of --sd-mm"
    )
    args = parser.parse_args(argv)
    rows: dict[str, Row] = {}
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="engine_sharpness_") as tmp:
        workdir = Path(tmp)
        if "plan" in args.protocols and args.plan is None:
            args.plan = planned_in_ranges(workdir, 120.0)
        if args.brute:
            for protocol in args.protocols:
                for arm_seed in args.arms:
                    brute_force(protocol, arm_seed, args, workdir)
            return 0
        print(f"{'protocol / arm':22} runs valid V&WRONG inv&right {calibration.calibration_header()}  worst|z|")
        for protocol in args.protocols:
            pooled = Row()
            for arm_seed in args.arms:
                row = run_arm(protocol, arm_seed, args, workdir)
                rows[f"{protocol}/{arm_seed}"] = row
                print_row(f"{protocol} arm {arm_seed}", row)
                pooled.pool(row)
            c = pooled.two_sided.calibration()
            print(
                f"{protocol + ' (all arms)':22} {pooled.runs:4} {pooled.valid:5} {pooled.valid_wrong:7} "
                f"{pooled.invalid_right:9} {calibration.calibration_columns(c)}",
                flush=True,
            )
    print("acceptance: " + "; ".join(acceptance(rows)))
    print(f"({sum(r.runs for r in rows.values())} sessions in {time.monotonic() - start:.0f} s)")
    if args.json is not None:
        summary = {
            label: {
                **r.counts_json(),
                "z_rms": r.two_sided.calibration().z_rms,
                "samples": r.two_sided.samples,
                "inflation": {k: float(np.median(v)) for k, v in r.inflation.items()},
            }
            for label, r in rows.items()
        }
        args.json.write_text(json.dumps(summary, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
