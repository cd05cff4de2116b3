"""Sharpness of the marker-placement term: one arm, markers re-placed every session, tared sensor.

Usage::

    python bench/placement_sharpness.py --sessions 12
    python bench/placement_sharpness.py --sessions 32 --scenario planned
    python bench/placement_sharpness.py --sessions 32 --delay-offsets   # the timing fix, monkeypatched

Every session is the same simulated human arm (``bsp_ros.core.simulation.human_arm_cell``, the same subject and
protocol) with its own noise seed and its own skin-marker placement: each chain point (shoulder, elbow, wrist,
hand/contact point) is offset from its joint centre by a draw of ``--sd-mm`` sd per in-plane axis (along and normal
to its segment; isotropic, so the same as y and z), given to ``MarkerSpec.skin_offset_m``. The sensor has no zero
offset and is identified as tared (``zero_sd_n = zero_sd_nm = 0``): the std holds sensor noise, marker placement
and whatever else the identification adds, not the untared zero term.

Per static moment, Coulomb amplitude and perpendicular moment the table gives, over the sessions:

- ``rms err``: RMS of estimate - truth; ``spread``: the estimates' sd;
- ``med std``: the median reported std; ``plc``: the median ``marker_placement`` budget term; ``plc@sd``: the same
  at the assumed sd (the term over the data's ``scale_from_data``); ``noise``: the median ``sensor_noise`` term;
- ``fd plc``: the placement sd by brute force on the first session that kept the default model: each chain point's
  offset moved by +-``--fd-step-mm`` along each axis (same noise seed, re-simulated and re-identified), the central
  difference per axis, ``sqrt(sum (d value / d offset)^2 sd^2)``; ``ledger/fd``: that session's ledger term over it
  (1: the first-order covariance is right);
- ``luck``: ``fd plc`` over the RMS of the errors the finite differences predict from the offsets actually drawn
  (1 on average; how sharp a perfectly honest std would look on these draws: with 12 sessions its 5-95 % range is
  about 0.75-1.5); ``sharp``: median std over RMS error (1 ideal); ``z rms``.

Also printed: how often the wrench-marker delay estimate was applied (the simulated delay is 0) and its median
magnitude. ``--delay-offsets`` monkeypatches the delay profile's linear model (``timing._JointColumns.of``) to fit
the perpendicular moments and the markers' offset columns (``placement_columns`` on 0.5 s averaged torques) beside
its gravity and friction columns: with 2 mm placement the unpatched profile applies a delay of tens of ms in most
sessions, which moves the Coulomb amplitudes outside the placement term. ``--known-delay`` gives the delay (0)
instead of estimating it. The estimator's ``sensor_noise`` term is the HAC sandwich of the residual the offsets leave
(``steps.add_marker_placement``), so that the part of their effect the model cannot follow is not counted twice.

The table is over the sessions that kept the default passive model (``quality.marker_placement`` present); a session
whose model checks replaced the model (an elastic false alarm: a family of models, a much wider std) is listed
below it with its largest |z|.
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from typing import Any

import numpy as np

from bsp_ros.core import simulation as sim
from bsp_ros.core.pipeline import IdentifyOptions, identify_session

PARAMETERS = (
    ("segments", "upper_arm", "static_moment_kgm"),
    ("segments", "forearm", "static_moment_kgm"),
    ("segments", "hand", "static_moment_kgm"),
    ("joints", "shoulder", "coulomb_nm"),
    ("joints", "elbow", "coulomb_nm"),
    ("joints", "wrist", "coulomb_nm"),
    ("segments", "upper_arm", "perpendicular_moment_kgm"),
    ("segments", "forearm", "perpendicular_moment_kgm"),
    ("segments", "hand", "perpendicular_moment_kgm"),
)
N_POINTS = 4  # shoulder, elbow, wrist, hand (the contact point)


def offsets_m(seed: int, sd_m: float) -> np.ndarray:
    """(4, 2) the session's skin offsets ``(along, normal)`` per chain point, m: N(0, sd^2) each, own stream."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 2002]))
    return rng.normal(0.0, sd_m, (N_POINTS, 2))


def trajectory(scenario: str) -> Any:
    """The protocol: the cell's sines, ``bsp plan``'s protocol (``bench/coverage.py``), or the sines 4x faster."""
    if scenario == "planned":
        from coverage import _plan

        return _plan().trajectory
    base = sim.human_arm_cell().trajectory
    if scenario == "fast":
        return dataclasses.replace(base, period_s=tuple(p / 4.0 for p in base.period_s))
    return base


def identify(seed: int, offsets: np.ndarray, motion: Any, duration_s: float, options: IdentifyOptions) -> dict:
    """Simulate one session with these skin offsets and identify it: per parameter value, std, terms and truth."""
    spec = sim.human_arm_cell(seed=seed, duration_s=duration_s, trajectory=motion)
    markers = dataclasses.replace(spec.markers, skin_offset_m=tuple(tuple(map(float, pair)) for pair in offsets))
    simulated = sim.simulate_cell(dataclasses.replace(spec, markers=markers))
    document = identify_session(simulated.session, options)
    truth = simulated.truth.to_dict()
    quality = document["quality"]
    placement = quality.get("marker_placement")  # absent where the model checks replaced the model (a family)
    out: dict[str, Any] = {
        "checked": placement is not None,
        "scale": float(placement["scale_from_data"]) if placement else 1.0,
        "delay_s": float(quality["timing"]["wrench_delay_s"]),
        "valid": bool(quality["valid"]),
    }
    for group, owner, key in PARAMETERS:
        q = document[group][owner][key]
        budget = q.get("budget", {})
        out[f"{key}/{owner}"] = {
            "value": float(q["value"]),
            "std": float(q["std"]),
            "truth": float(truth[group][owner][key]),
            "placement": float(budget.get("marker_placement", 0.0)),
            "noise": float(budget.get("sensor_noise", 0.0)),
        }
    return out


def finite_differences(
    seed: int, offsets: np.ndarray, motion: Any, duration_s: float, options: IdentifyOptions, step_m: float, sd_m: float
) -> dict[str, np.ndarray]:
    """Per parameter (8,) the response to one sd of each chain point's along and normal offset (central differences
    of re-simulated sessions, same noise seed)."""
    responses: dict[str, np.ndarray] = {}
    for k in range(2 * N_POINTS):
        values = []
        for sign in (1.0, -1.0):
            moved = offsets.copy()
            moved[k // 2, k % 2] += sign * step_m
            values.append(identify(seed, moved, motion, duration_s, options))
        for name in (f"{key}/{owner}" for _, owner, key in PARAMETERS):
            slope = (values[0][name]["value"] - values[1][name]["value"]) / (2.0 * step_m)
            responses.setdefault(name, np.zeros(2 * N_POINTS))[k] = slope * sd_m
    return responses


def patch_delay_profile() -> None:
    """Monkeypatch the wrench-delay profile's linear model to fit the perpendicular moments and the markers' offset
    columns beside gravity and friction (the proposed change to ``timing._JointColumns.of``)."""
    from bsp_ros.core.identification import timing
    from bsp_ros.core.identification.joint.placement_covariance import averaged_torques
    from bsp_ros.core.identification.placement import placement_columns
    from bsp_ros.core.model import GRAVITY_M_S2, absolute_angles_rad

    original = timing._JointColumns.of.__func__  # type: ignore[attr-defined]

    def of(cls: type, data: Any, passive: Any) -> Any:
        base = original(cls, data, passive)
        n, p = data.n_joints, base.n_parameters
        design, moment = base.products(np.ones_like(data.tau_nm), data.tau_nm)
        beta = np.linalg.lstsq(design, moment, rcond=None)[0][:n]  # for the offsets' columns only
        zeros = np.zeros_like(data.q_rad)
        offset = placement_columns(
            data.q_rad, zeros, zeros, data.lengths_m, averaged_torques(data), np.concatenate((beta, np.zeros(2 * n)))
        )
        sine = -GRAVITY_M_S2 * np.sin(absolute_angles_rad(data.q_rad))
        m = offset.shape[2]
        columns, indices = [], []
        for i in range(n):
            columns.append(np.hstack((base.columns[i], sine[:, i:], offset[:, i, :])))
            indices.append(np.concatenate((base.indices[i], p + np.arange(i, n), p + n + np.arange(m))))
        return cls(columns, indices, p + n + m)

    timing._JointColumns.of = classmethod(of)  # type: ignore[method-assign,assignment]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sessions", type=int, default=12, help="sessions of the one arm (default 12)")
    parser.add_argument("--seed", type=int, default=0, help="first session's seed (default 0)")
    parser.add_argument("--sd-mm", type=float, default=2.0, help="placement sd per axis, drawn and assumed (mm)")
    parser.add_argument("--scenario", choices=("sines", "planned", "fast"), default="sines")
    parser.add_argument("--duration", type=float, default=120.0, help="session length, s (default 120)")
    parser.add_argument("--fd-step-mm", type=float, default=1.0, help="finite-difference step (mm; 0: none)")
    parser.add_argument("--delay-offsets", action="store_true", help="the delay profile also fits the offsets")
    parser.add_argument("--known-delay", action="store_true", help="give the wrench delay (0), do not estimate")
    args = parser.parse_args()
    if args.delay_offsets:
        patch_delay_profile()
    sd_m = 1e-3 * args.sd_mm
    options = IdentifyOptions(
        zero_sd_n=0.0, zero_sd_nm=0.0, marker_placement_sd_m=sd_m, wrench_delay_s=0.0 if args.known_delay else None
    )
    motion = trajectory(args.scenario)
    started = time.perf_counter()
    seeds = range(args.seed, args.seed + args.sessions)
    drawn = {seed: offsets_m(seed, sd_m) for seed in seeds}
    rows = [identify(seed, drawn[seed], motion, args.duration, options) for seed in seeds]
    fd = {}
    # The brute force on the first session whose placement was judged (its default model kept: a model switch under
    # a 1 mm step is no derivative).
    fd_index = next((i for i, r in enumerate(rows) if r["checked"] and r["valid"]), None)
    if args.fd_step_mm > 0 and fd_index is not None:
        fd_seed = seeds[fd_index]
        fd = finite_differences(fd_seed, drawn[fd_seed], motion, args.duration, options, 1e-3 * args.fd_step_mm, sd_m)
    print(
        f"scenario {args.scenario}, {args.sessions} sessions from seed {args.seed}, placement sd {args.sd_mm:g} mm,"
        f" {'known delay' if args.known_delay else 'delay estimated'}"
        f"{' (profile fits the offsets)' if args.delay_offsets else ''}"
        ";"
        f" valid {sum(r['valid'] for r in rows)}"
    )
    print(
        f"{'parameter':35s} {'rms err':>8s} {'spread':>8s} {'med std':>8s} {'plc':>8s} {'plc@sd':>8s} {'noise':>8s}"
        f" {'fd plc':>8s} {'ledger/fd':>9s} {'luck':>5s} {'sharp':>5s} {'z rms':>5s}"
    )
    kept = [i for i, r in enumerate(rows) if r["checked"] and r["valid"]]
    all_rows = rows
    rows = [all_rows[i] for i in kept]
    z_pooled = []
    for _, owner, key in PARAMETERS:
        name = f"{key}/{owner}"
        error = np.array([r[name]["value"] - r[name]["truth"] for r in rows])
        std = np.array([r[name]["std"] for r in rows])
        placement = np.array([r[name]["placement"] for r in rows])
        at_sd = placement / np.array([r["scale"] for r in rows])
        noise = np.array([r[name]["noise"] for r in rows])
        rms = float(np.sqrt(np.mean(error**2)))
        z = error / std
        if key != "perpendicular_moment_kgm":
            z_pooled.extend(z.tolist())
        fd_sd = ratio = luck = float("nan")
        if fd:
            fd_sd = float(np.linalg.norm(fd[name]))
            ratio = all_rows[fd_index][name]["placement"] / all_rows[fd_index]["scale"] / fd_sd
            predicted = np.array([fd[name] @ (drawn[seeds[i]].ravel() / sd_m) for i in kept])
            luck = fd_sd / float(np.sqrt(np.mean(predicted**2)))
        print(
            f"{name:35s} {rms:8.5f} {np.std(error, ddof=1):8.5f} {np.median(std):8.5f} {np.median(placement):8.5f}"
            f" {np.median(at_sd):8.5f} {np.median(noise):8.5f} {fd_sd:8.5f} {ratio:9.2f} {luck:5.2f}"
            f" {np.median(std) / rms:5.2f} {np.sqrt(np.mean(z**2)):5.2f}"
        )
    for i, r in enumerate(all_rows):
        if i not in kept:
            worst = max(
                abs(r[n]["value"] - r[n]["truth"]) / r[n]["std"] for n in (f"{k}/{o}" for _, o, k in PARAMETERS)
            )
            print(
                f"seed {seeds[i]}: model replaced by the checks (or invalid), left out above; largest |z| {worst:.2f}"
            )
    delays = np.array([r["delay_s"] for r in rows])
    scales = np.array([r["scale"] for r in rows])
    print(
        f"static moments and Coulomb amplitudes pooled: z RMS {np.sqrt(np.mean(np.square(z_pooled))):.2f};"
        f" delay applied in {int((delays != 0).sum())}/{len(rows)} sessions"
        f" (median |delay| {1e3 * np.median(np.abs(delays)):.1f} ms, max {1e3 * np.abs(delays).max():.1f} ms);"
        f" placement scale from data: median {np.median(scales):.2f}, max {scales.max():.2f}"
        f" ({time.perf_counter() - started:.0f} s)"
    )


if __name__ == "__main__":
    main()
