"""Realism benchmark: the estimator on simulated cells with one everyday nuisance at a time, with and without tare.

Usage: ``python bench/realism.py [--seeds 3] [--duration 120] [--only NAME ...] [--no-tare] [--json OUT]``

For every nuisance and seed, a 3-segment human-arm session is simulated (``bsp_ros.core.simulation``) and identified
with the default options (``bsp_ros.core.pipeline.identify_session``, body mass and height given); "with tare" first
simulates the cell's tare recording (20 s, a minute before the session, the sensor swung 20 deg in roll and
pitch, orientation known as from ``/tf``), estimates it (``bsp_ros.core.tare``) and applies it. Per nuisance and
mode the table shows, over the seeds: the worst static-moment error (% of the truth, worst segment, worst
seed), the worst Coulomb error (%), the largest |z| = |estimate - truth| / std over every data-sourced parameter
(``source`` data or data+prior, invalid estimates included), how many estimates were valid, both error rates:
valid yet some parameter beyond 3 std ("v&wrong") and invalid with every parameter within 3 std ("inv&right": a
right result thrown away), two-sided calibration over the data-sourced parameters of the valid estimates
(``bench/calibration.py``): z RMS with z = (estimate - truth) / std (1 for an honest std) and the shares within 1
and 2 std (68 %, 95 % for an honest std), the sharpness over the seeds (one arm, re-simulated; the nuisance's
seeded directions change with it): per parameter the median std over the RMS error across the seeds (1 ideal),
per kind (static moments "SM", Coulomb amplitudes "C", masses "m") the median (range) over its parameters, and
the most frequent kinds of warning (the codes of the findings that qualify or annotate it, with their joint or
segment); the totals of both rates and the pooled calibration close the table.
Sensor nuisances (offset, drift, handle) pick a seeded random direction per seed.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import json
import math
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from calibration import calibration_columns, calibration_header, sharpness_columns, sharpness_header, summary_line
from finding_kinds import warning_kinds
from scoring import Counts, Scored, scored

from bsp_ros.core.findings import FindingCode
from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.core.simulation import (
    CellSpec,
    MarkerSpec,
    TareSpec,
    human_arm_cell,
    simulate_cell,
    simulate_tare,
    tare_rotations,
)
from bsp_ros.core.tare import estimate_tare
from bsp_ros.errors import BspError

COULOMB = (0.5, 0.28, 0.06)
TARE = TareSpec(duration_s=20.0, start_offset_s=-60.0, swing_rpy_deg=(20.0, 20.0, 0.0))


def _direction(seed: int) -> np.ndarray:
    v = np.random.default_rng([seed, 11]).standard_normal(3)
    return v / np.linalg.norm(v)


def _sensor(spec: CellSpec, **changes: Any) -> CellSpec:
    return dataclasses.replace(spec, sensor=dataclasses.replace(spec.sensor, **changes))


def _passive(spec: CellSpec, **changes: Any) -> CellSpec:
    return dataclasses.replace(spec, passive=dataclasses.replace(spec.passive, **changes))


def _offset(newtons: float) -> Callable[[CellSpec, int], CellSpec]:
    return lambda s, seed: _sensor(s, force_bias_n=tuple(newtons * _direction(seed)))


NUISANCES: dict[str, Callable[[CellSpec, int], CellSpec]] = {
    "none": lambda s, seed: s,
    "friction tanh 2 mrad/s": lambda s, seed: _passive(s, friction_transition_rad_s=0.002),
    "friction tanh 5 mrad/s": lambda s, seed: _passive(s, friction_transition_rad_s=0.005),
    "Stribeck x1.5 at 10 mrad/s": lambda s, seed: _passive(s, stribeck_ratio=1.5, stribeck_speed_rad_s=0.01),
    "F/T offset 0.2 N": _offset(0.2),
    "F/T offset 1 N": _offset(1.0),
    "F/T offset 3 N": _offset(3.0),
    "F/T moment offset 0.05 Nm": lambda s, seed: _sensor(s, torque_bias_nm=tuple(0.05 * _direction(seed + 100))),
    "F/T drift 5 mN/s": lambda s, seed: _sensor(s, force_drift_n_per_s=tuple(0.005 * _direction(seed))),
    "handle 0.3 kg": lambda s, seed: _sensor(s, handle_mass_kg=0.3, handle_com_m=(0.0, 0.02, 0.05)),
    "3 N offset + 0.3 kg handle": lambda s, seed: _sensor(
        s, force_bias_n=tuple(3.0 * _direction(seed)), handle_mass_kg=0.3, handle_com_m=(0.0, 0.02, 0.05)
    ),
    "elastic offset 0.05 Nm": lambda s, seed: _passive(s, offset_nm=(0.05, 0.05, 0.05)),
    "elastic offset 0.2 Nm": lambda s, seed: _passive(s, offset_nm=(0.2, 0.2, 0.2)),
    "elbow stiffness 1.2 Nm/rad": lambda s, seed: _passive(
        s, stiffness_nm_per_rad=(0.0, 1.2, 0.0), neutral_rad=(0.0, math.radians(107.0), 0.0)
    ),
    "skin markers 1 cm": lambda s, seed: dataclasses.replace(
        s, markers=MarkerSpec(skin_offset_m=tuple(tuple(0.01 * _direction(seed + k)[:2]) for k in range(4)))
    ),
    "lost /tf_static": lambda s, seed: _sensor(s, tf_static=False),
    "spikes 1 kN in 0.1 %": lambda s, seed: _sensor(s, spike_fraction=0.001, spike_n=1000.0),
    "absurd 1e30 N in 0.02 %": lambda s, seed: _sensor(s, spike_fraction=0.0002, spike_n=1e30),
    "30 s session": lambda s, seed: dataclasses.replace(s, duration_s=30.0),
}

# Notes of every session (the prior used; the data layer's count of samples without angles): not counted as warnings.
_ROUTINE = frozenset({str(FindingCode.PRIOR_NOTE), str(FindingCode.DATA_NOTE)})


def _run(spec: CellSpec, tare: bool) -> dict[str, Any]:
    options = IdentifyOptions(subject=SubjectInfo(75.0, 1.78, "male"))
    if tare:
        recording = simulate_tare(spec, TARE)
        t_s = (recording.wrench.t_ns - spec.start_ns) * 1e-9 - TARE.start_offset_s
        rotations = tare_rotations(spec, TARE, t_s) if spec.sensor.tf_static else None
        w = recording.wrench
        options = dataclasses.replace(
            options, tare=estimate_tare(w.t_ns, w.force_n, w.torque_nm, w.frame_id, rotations)
        )
    simulated = simulate_cell(spec)
    truth = simulated.truth.to_dict()
    document = identify_session(simulated.session, options)
    moment_err, coulomb_err = [], []
    for segment, q in document["segments"].items():
        value, true = q["static_moment_kgm"]["value"], truth["segments"][segment]
        value = math.nan if value is None else value
        moment_err.append(100.0 * abs(value - true["static_moment_kgm"]) / true["static_moment_kgm"])
    for joint, q in document["joints"].items():
        if "coulomb_nm" not in q:
            continue
        value = math.nan if q["coulomb_nm"]["value"] is None else q["coulomb_nm"]["value"]
        true_c = truth["joints"][joint]["coulomb_nm"]
        coulomb_err.append(100.0 * abs(value - true_c) / true_c)
    run = scored(document, truth)
    return {
        "valid": run.valid,
        "moment_err_pct": float(np.nanmax(moment_err)) if not np.isnan(moment_err).all() else math.nan,
        "coulomb_err_pct": float(np.nanmax(coulomb_err))
        if coulomb_err and not np.isnan(coulomb_err).all()
        else math.nan,
        "max_z": run.max_z,
        "residuals": run.residuals,
        "warnings": warning_kinds(document["quality"]),
        "message": document["quality"].get("message", ""),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=3, help="seeds per nuisance (default 3)")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--duration", type=float, default=120.0, help="session length, s (default 120)")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="nuisances whose name contains one of these")
    parser.add_argument("--no-tare", action="store_true", help="skip the runs with a tare")
    parser.add_argument("--json", metavar="OUT", help="write every run's figures here")
    args = parser.parse_args(argv)
    names = [n for n in NUISANCES if not args.only or any(o.lower() in n.lower() for o in args.only)]
    modes = (False,) if args.no_tare else (False, True)
    runs: list[dict[str, Any]] = []
    pooled = Counts()
    header = (
        f"{'nuisance':28s} {'tare':4s} {'moment %':>9s} {'Coulomb %':>9s} {'max|z|':>7s} {'valid':>6s}"
        f" {'v&wrong':>7s} {'inv&right':>9s} {calibration_header()} {sharpness_header()}"
        "  warnings (runs)"
    )
    print(header)
    print("-" * len(header))
    started = time.perf_counter()
    for name in names:
        for tare in modes:
            results = []
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                spec = NUISANCES[name](human_arm_cell(duration_s=args.duration, seed=seed), seed)
                try:
                    result = _run(spec, tare)
                except BspError as error:  # an error is a result here: it names the bad input
                    result = {
                        "valid": False,
                        "moment_err_pct": math.nan,
                        "coulomb_err_pct": math.nan,
                        "max_z": math.nan,
                        "residuals": {},
                        "warnings": [f"error: {type(error).__name__}"],
                        "message": str(error),
                    }
                results.append(result)
                runs.append({"nuisance": name, "tare": tare, "seed": seed, "result": result})
            counts = Counts()
            for r in results:
                r["verdict"] = counts.count(Scored.from_residuals(r["valid"], r["residuals"])).verdict
            pooled.pool(counts)
            # Each run's kinds once, in the order it gave them (a set's order changes with the hash seed).
            once = (k for r in results for k in dict.fromkeys(r["warnings"]))
            kinds = collections.Counter(k for k in once if k not in _ROUTINE)
            common = "; ".join(f"{k} ({c})" for k, c in kinds.most_common(2)) or "-"
            row = (
                f"{name:28s} {'yes' if tare else 'no':4s} "
                f"{max(r['moment_err_pct'] for r in results):9.3g} {max(r['coulomb_err_pct'] for r in results):9.3g} "
                f"{max(r['max_z'] for r in results):7.3g} {counts.valid:>3d}/{counts.runs:<2d} {counts.valid_wrong:>7d}"
                f" {counts.invalid_right:>9d} {calibration_columns(counts.two_sided.calibration())}"
                f" {sharpness_columns(counts.two_sided.sharpness())}  {common}"
            )
            print(row, flush=True)
    total, wrong, thrown = pooled.runs, pooled.valid_wrong, pooled.invalid_right
    print(
        f"valid-and-wrong {wrong}/{total} runs ({100 * wrong / max(total, 1):.1f} %), "
        f"invalid-and-right {thrown}/{total} ({100 * thrown / max(total, 1):.1f} %)"
    )
    # No pooled sharpness: over nuisances one parameter's errors would mix them.
    print(summary_line("pooled over the valid runs", pooled.two_sided, sharpness=False))
    print(
        f"({len(runs)} runs in {time.perf_counter() - started:.0f} s; seeds {args.first_seed}..."
        f"{args.first_seed + args.seeds - 1}, {args.duration:g} s sessions)"
    )
    if args.json:
        with open(args.json, "w", encoding="utf-8") as stream:
            json.dump(
                [{**{k: v for k, v in run.items() if k != "result"}, **run["result"]} for run in runs], stream, indent=1
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
