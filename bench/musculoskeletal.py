"""Musculoskeletal benchmark: `bsp identify` on OpenSim's arm26 (relaxed two-joint muscles), its error rates.

Usage: ``python bench/musculoskeletal.py [--seeds 3] [--quick] [--shares 0.01 0.03 0.1 0.5 1.5]
[--protocols paper planned] [--models coulomb ...] [--duration 120] [--all-quantities] [--json OUT]``

For every passive strength (the muscles' maximum isometric forces scaled so that the largest per-joint RMS
passive moment is that share of the RMS gravity torque on the paper's protocol; 0 = "rigid", muscles off: what
the arm's geometry alone does, COM off the segment axis and oblique joint axes), protocol (the paper's 2-joint
sine, ``bsp_ros.core.simulation``; a plan of ``bsp_ros.core.planning`` within elevation 42-70 deg) and seed, a
session of ``test/physics/opensim_cell.py`` is written as a bag and identified with ``bsp identify --json``
(in-process, ``bsp_ros.cli.main``) with the default passive model and every ``--passive`` model the tool offers
(each valid combination of ``bsp_ros.core.identification.passive.TERMS``) or a finding names
(``values.passive_option``). Every data-sourced quantity (source ``data`` / ``data+prior``) that the truth has is
scored by ``|z| = |value - truth| / std``: the static moments (with ``--all-quantities`` also lengths, masses, COMs,
first moments, inertias and the joints' Coulomb level, whose truth is 0) and, where the estimate has
``joints.<joint>.passive_curve``, its points against the truth's curve. Per row: runs, valid, valid-and-wrong
(some |z| > 3), invalid-and-right (every |z| <= 3), two-sided calibration over the scored quantities of the valid
runs but not the curves, whose points are not independent (``bench/calibration.py``: z RMS with
z = (value - truth) / std, 1 for an honest std; the shares within 1 and 2 std, 68 % and 95 % for an honest std),
the sharpness over the seeds (arm26 is one arm, a seed re-draws the noise: per quantity the median std over the RMS
error across the valid runs, 1 ideal; per kind, static moments "SM", Coulomb amplitudes "C" and masses "m" with
``--all-quantities``, the median and range over its quantities), the worst |z| over valid runs and over all, the
median over valid runs of the largest static-moment error (% of the truth) and of the largest passive-curve error
(RMS over the truth curve's range, % of its RMS), how many runs are "accurate" (issue 20's target: valid, static
moments within 3 % and 3 std, curves within 10 % RMS), the most common cause of the invalid ones (the first
invalid finding's code and where, or the error line of a run that wrote no estimate).
``--quick``: one seed, 60 s, rigid and three strengths, three models (and suggestions). ``--planar``: arm26 with
both joint axes made exactly lateral. ``--trunk-tilt-deg DEG``: each session is also recorded with arm26's ground
(the trunk, with the shoulder and the muscles' origins) turned by DEG about world x, the same motion relative to it,
and both recordings are identified together (``bsp identify UPRIGHT TILTED --trunk-tilt-deg 0 DEG``): rows
``PROTOCOL+DEG``, scored against the upright session's truth.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import dataclasses
import io
import itertools
import json
import math
import re
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
from calibration import calibration_columns, calibration_header, sharpness_columns, sharpness_header
from finding_kinds import NO_FINDING, cause_of, passive_options
from scoring import WRONG_Z, Counts, Scored

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "test" / "physics"))

from bsp_ros.cli import main as bsp_main  # noqa: E402
from bsp_ros.core.identification.passive import TERMS, PassiveModel  # noqa: E402
from bsp_ros.errors import InputError  # noqa: E402

SHARES = (0.0, 0.01, 0.03, 0.1, 0.5, 1.5)  # 0: the rigid arm (muscles off), the geometry alone
QUICK_SHARES = (0.0, 0.01, 0.1, 1.5)
PROTOCOLS = ("paper", "planned")
DEFAULT = "default"  # no --passive option
QUICK_MODELS = (DEFAULT, "coulomb+offset+stiffness", "+".join(TERMS))
SOURCES = ("data", "data+prior")
SEGMENT_KEYS = ("static_moment_kgm",)
ALL_SEGMENT_KEYS = (
    "static_moment_kgm",
    "length_m",
    "mass_kg",
    "com_m",
    "first_moment_kgm",
    "perpendicular_moment_kgm",
    "inertia_kgm2",
    "inertia_com_kgm2",
    "grouped_inertia_kgm2",
)
ALL_JOINT_KEYS = ("coulomb_nm",)
_NUMBER = re.compile(r"[-+]?\d[\d.e+-]*%?")


def offered_models() -> list[str]:
    """Every valid ``--passive`` model out of the estimator's terms, shortest first."""
    models = []
    for size in range(1, len(TERMS) + 1):
        for terms in itertools.combinations(TERMS, size):
            try:
                models.append(PassiveModel(terms).label)
            except InputError:  # e.g. a stiffness without its offset
                continue
    return models


def identify(bag: Path | list[Path], model: str, out: Path, extra: list[str]) -> dict[str, Any]:
    """Run ``bsp identify BAG... --json OUT`` in-process; the estimate, or ``{"error": message}``."""
    bags = bag if isinstance(bag, list) else [bag]
    argv = ["identify", *map(str, bags), "--json", str(out), "--format", "none", *extra]
    if model != DEFAULT:
        argv += ["--passive", model]
    stderr = io.StringIO()
    out.unlink(missing_ok=True)
    try:
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(stderr):
            code = bsp_main(argv)
    except Exception as error:  # a traceback is a finding too: report it, keep benchmarking
        return {"error": f"crash: {type(error).__name__}: {error}"}
    if not out.exists():
        lines = stderr.getvalue().strip().splitlines()
        return {"error": f"exit {code}: {lines[-1] if lines else 'no estimate written'}"}
    document: dict[str, Any] = json.loads(out.read_text())
    return document


def _curve_z(estimate: dict[str, Any], truth: dict[str, Any]) -> list[float]:
    """|z| of each estimated passive-curve point inside the truth curve's range."""
    angle = np.asarray(estimate.get("angle_deg", []), dtype=float)
    value = np.asarray(estimate.get("moment_nm", []), dtype=float)
    std = np.asarray(estimate.get("std_nm", []), dtype=float)
    true_angle, true_moment = np.asarray(truth["angle_deg"]), np.asarray(truth["moment_nm"])
    inside = (angle >= true_angle.min()) & (angle <= true_angle.max()) & (std > 0)
    if not inside.any():
        return []
    reference = np.interp(angle[inside], true_angle, true_moment)
    return (np.abs(value[inside] - reference) / std[inside]).tolist()


def residuals(document: dict[str, Any], truth: dict[str, Any], all_quantities: bool) -> dict[str, tuple[float, float]]:
    """(value - truth, std) of every scored data-sourced quantity with a truth and a std, keyed ``<key>/<owner>``.

    Parameters
    ----------
    document : dict
        The estimate (``bsp identify --json``).
    truth : dict
        The session's truth.json.
    all_quantities : bool
        Every quantity of ``ALL_SEGMENT_KEYS`` and ``ALL_JOINT_KEYS``; else the static moments alone.

    Returns
    -------
    dict
        ``key/owner -> (signed error, std)`` in the quantity's unit (the passive curves are not included).
    """
    out = {}
    groups = (
        ("segments", ALL_SEGMENT_KEYS if all_quantities else SEGMENT_KEYS),
        ("joints", ALL_JOINT_KEYS if all_quantities else ()),
    )
    for group, keys in groups:
        for owner, quantities in document.get(group, {}).items():
            true_owner = truth[group].get(owner, {})
            for key in keys:
                q = quantities.get(key)
                if not isinstance(q, dict) or q.get("source") not in SOURCES or key not in true_owner:
                    continue
                if q.get("value") is None or not q.get("std"):
                    continue
                out[f"{key}/{owner}"] = (float(q["value"]) - float(true_owner[key]), float(q["std"]))
    return out


def score(document: dict[str, Any], truth: dict[str, Any], all_quantities: bool) -> dict[str, float]:
    """``{"<owner>.<key>": |z|}`` for every data-sourced quantity with a truth (passive curves: the worst point)."""
    z = {}
    for name, (error, std) in residuals(document, truth, all_quantities).items():
        key, owner = name.split("/", 1)
        z[f"{owner}.{key}"] = abs(error) / std
    for joint, quantities in document.get("joints", {}).items():
        curve, true_curve = quantities.get("passive_curve"), truth["joints"].get(joint, {}).get("passive_curve")
        if isinstance(curve, dict) and true_curve:
            points = _curve_z(curve, true_curve)
            if points:
                z[f"{joint}.passive_curve"] = max(points)
    return z


def accuracy(document: dict[str, Any], truth: dict[str, Any]) -> dict[str, float]:
    """Issue 20's accuracy target, per run: the largest static-moment error (% of the truth) and the largest
    passive-curve error (RMS over the truth curve's range, % of the truth curve's RMS)."""
    static = [
        100.0
        * abs(q["value"] - truth["segments"][name]["static_moment_kgm"])
        / abs(truth["segments"][name]["static_moment_kgm"])
        for name, quantities in document.get("segments", {}).items()
        if isinstance(q := quantities.get("static_moment_kgm"), dict)
        and q.get("value") is not None
        and name in truth["segments"]
    ]
    curves = []
    for joint, quantities in document.get("joints", {}).items():
        curve, true_curve = quantities.get("passive_curve"), truth["joints"].get(joint, {}).get("passive_curve")
        if not (isinstance(curve, dict) and true_curve):
            continue
        true_angle, true_moment = np.asarray(true_curve["angle_deg"]), np.asarray(true_curve["moment_nm"])
        angle, moment = np.asarray(curve["angle_deg"], dtype=float), np.asarray(curve["moment_nm"], dtype=float)
        inside = (angle >= true_angle.min()) & (angle <= true_angle.max())
        reference = np.interp(angle[inside], true_angle, true_moment)
        if inside.sum() >= 2 and np.any(reference):
            curves.append(100.0 * math.sqrt(np.mean((moment[inside] - reference) ** 2) / np.mean(reference**2)))
    return {"static_pct": max(static, default=math.nan), "curve_rms_pct": max(curves, default=math.nan)}


def _message(document: dict[str, Any]) -> str:
    """Why a run is invalid: the first invalid finding's code and where, or the error line of a run that wrote no
    estimate (numbers blanked, so that alike errors count together)."""
    if "error" in document:
        return _NUMBER.sub("#", str(document["error"]))[:70]
    cause = cause_of(document.get("quality", {}))
    return "invalid (no finding)" if cause == NO_FINDING else cause


def session_bag(
    cell: Any,
    share: float,
    protocol: str,
    seed: int,
    duration_s: float,
    where: Path,
    planar: bool = False,
    tilt_deg: float = 0.0,
) -> Path:
    """Simulate one arm26 session and write it (with truth.json) under ``where``; share 0: muscles off.
    ``tilt_deg``: the trunk tilted, the same motion relative to it, recorded 10 minutes later."""
    tilt = math.radians(tilt_deg)
    if share > 0:
        scale = cell.force_scale_for_share(share, planar)
        options = cell.CellOptions(force_scale=scale, planar=planar, trunk_tilt_rad=tilt)
    else:
        options = cell.CellOptions(muscles=False, planar=planar, trunk_tilt_rad=tilt)
    arm = cell.Arm26(options)
    trajectory = cell.PAPER_PROTOCOL if protocol == "paper" else _planned(cell, duration_s)
    if tilt_deg:
        trajectory = cell.TrunkTilted(trajectory, tilt)
    recording = cell.SessionOptions(duration_s=duration_s, seed=seed + (1000 if tilt_deg else 0))
    if tilt_deg:
        recording = dataclasses.replace(recording, start_ns=recording.start_ns + 600_000_000_000)
    run = cell.run_cell(arm, trajectory, recording)
    return Path(cell.write_bag(where / f"s{share:g}_{protocol}_{seed}_{tilt_deg:g}", run, seed=seed))


_PLANS: dict[float, Any] = {}


def _planned(cell: Any, duration_s: float) -> Any:
    if duration_s not in _PLANS:
        _PLANS[duration_s] = cell.planned_protocol(cell.Arm26(), duration_s)
    return _PLANS[duration_s]


def _row_text(key: tuple[float, str, str], runs: list[dict[str, Any]]) -> str:
    share, protocol, model = key
    counts = Counts()
    for r in runs:
        counts.count(Scored(valid=r["valid"], z=r["z"], residuals=r["residuals"]))
    valid = [r for r in runs if r["valid"]]
    messages = collections.Counter(r["message"] for r in runs if not r["valid"])
    common = f"{messages.most_common(1)[0][0]} ({messages.most_common(1)[0][1]})" if messages else "-"

    # Issue 20: valid, static moments within 3 % and 3 std, passive curves within 10 % RMS.
    accurate = [
        r for r in valid if r["worst_z"] <= WRONG_Z and r["static_pct"] <= 3.0 and not r["curve_rms_pct"] > 10.0
    ]

    def median(rows: list[dict[str, Any]], key: str) -> str:
        values = [r[key] for r in rows if math.isfinite(r[key])]
        return f"{np.median(values):.1f}" if values else "-"

    def worst(rows: list[dict[str, Any]]) -> str:
        values = [r["worst_z"] for r in rows if r["z"]]
        return f"{max(values):.1f}" if values else "-"

    tally = counts.two_sided
    label = f"{100 * share:.3g}%" if share > 0 else "rigid"
    return (
        f"{label:>7s} {protocol:10s} {model:34s} {counts.runs:4d} {counts.valid:5d} {counts.valid_wrong:11d} "
        f"{counts.invalid_right:13d} {calibration_columns(tally.calibration())} {sharpness_columns(tally.sharpness())} "
        f"{worst(valid):>9s} {worst(runs):>7s} {median(valid, 'static_pct'):>8s} "
        f"{median(valid, 'curve_rms_pct'):>8s} {len(accurate):8d}  {common}"
    )


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark; print the table (and write the per-run records as JSON on request)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=3, help="seeds per strength and protocol (default 3)")
    parser.add_argument(
        "--quick", action="store_true", help="1 seed, 60 s, rigid and strengths 1/10/150 %%, three models"
    )
    parser.add_argument("--shares", type=float, nargs="+", help=f"passive strengths, fraction of gravity {SHARES}")
    parser.add_argument("--protocols", nargs="+", choices=PROTOCOLS, default=list(PROTOCOLS))
    parser.add_argument("--models", nargs="+", help="passive models (default: the tool's default and all offered)")
    parser.add_argument("--duration", type=float, help="session length, s (default 120, --quick 60)")
    parser.add_argument("--all-quantities", action="store_true", help="score every data-sourced quantity")
    parser.add_argument("--identify-args", default="", help="more `bsp identify` options, e.g. '--body-mass 70'")
    parser.add_argument("--planar", action="store_true", help="both joint axes exactly lateral (a planar arm26)")
    parser.add_argument(
        "--trunk-tilt-deg",
        type=float,
        default=0.0,
        help="also record each session with the trunk tilted by this much and identify both together "
        "(rows PROTOCOL+DEG)",
    )
    parser.add_argument("--json", type=Path, help="write every run's scores here")
    args = parser.parse_args(argv)
    try:
        import opensim_cell as cell
    except ImportError as error:
        print(f"musculoskeletal: OpenSim is not importable ({error}): pip install opensim (CPython 3.11)")
        return 2
    shares = args.shares or (QUICK_SHARES if args.quick else SHARES)
    seeds = 1 if args.quick else args.seeds
    duration = args.duration or (60.0 if args.quick else 120.0)
    base_models = args.models or (list(QUICK_MODELS) if args.quick else [DEFAULT, *offered_models()])
    extra = args.identify_args.split()
    rows: dict[tuple[float, str, str], list[dict[str, Any]]] = collections.defaultdict(list)
    started = time.monotonic()
    with tempfile.TemporaryDirectory(prefix="bsp_musculoskeletal_") as tmp:
        where = Path(tmp)
        for share, protocol, seed in itertools.product(shares, args.protocols, range(seeds)):
            bag = session_bag(cell, share, protocol, seed, duration, where, args.planar)
            truth = json.loads((bag / "truth.json").read_text())
            cases: list[tuple[str, Path | list[Path], list[str]]] = [(protocol, bag, extra)]
            if args.trunk_tilt_deg:
                tilted = session_bag(cell, share, protocol, seed, duration, where, args.planar, args.trunk_tilt_deg)
                tilts = ["--trunk-tilt-deg", "0", f"{args.trunk_tilt_deg:g}"]
                cases.append((f"{protocol}+{args.trunk_tilt_deg:g}", [bag, tilted], [*extra, *tilts]))
            done: set[str] = set()
            for label, bags, arguments in cases:
                queue, done = list(base_models), set()
                while queue:
                    model = queue.pop(0)
                    if model in done:
                        continue
                    done.add(model)
                    document = identify(bags, model, where / "estimate.json", arguments)
                    z = {} if "error" in document else score(document, truth, args.all_quantities)
                    signed = {} if "error" in document else residuals(document, truth, args.all_quantities)
                    valid = bool(document.get("quality", {}).get("valid", False))
                    errors = {"static_pct": math.nan, "curve_rms_pct": math.nan}
                    if "error" not in document:
                        errors = accuracy(document, truth)
                    queue += [m for m in passive_options(document.get("quality", {})) if m not in done]
                    rows[(share, label, model)].append(
                        {
                            "seed": seed,
                            "valid": valid,
                            "z": z,
                            "worst_z": max(z.values(), default=math.nan),
                            "residuals": signed,
                            "message": "" if valid else _message(document),
                            **errors,
                        }
                    )
            print(
                f"  {share:g} {protocol} seed {seed}: {len(done)} models, {time.monotonic() - started:.0f} s",
                file=sys.stderr,
            )
    scored = "static moments" + (" and every data-sourced quantity with a truth" if args.all_quantities else "")
    shape = "planar" if args.planar else "oblique axes"
    print(f"arm26 (OpenSim, {shape}), {duration:g} s sessions, {seeds} seed(s); |z| over {scored} and passive curves")
    print(
        f"{'passive':>7s} {'protocol':10s} {'model':34s} {'runs':>4s} {'valid':>5s} {'valid+wrong':>11s} "
        f"{'invalid+right':>13s} {calibration_header()} {sharpness_header()} {'worst|z|v':>9s} {'all':>7s} "
        f"{'static%':>8s} {'curve%':>8s} {'accurate':>8s}  most common invalid message"
    )
    for key in sorted(rows, key=lambda k: (k[0], k[1], k[2] != DEFAULT, len(k[2]), k[2])):
        print(_row_text(key, rows[key]))
    print(f"({time.monotonic() - started:.0f} s)")
    if args.json:
        records = [{"share": k[0], "protocol": k[1], "model": k[2], "runs": v} for k, v in rows.items()]
        args.json.write_text(json.dumps(records, indent=1, default=float) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
