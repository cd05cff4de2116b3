"""Live realism benchmark: the windowed identifier's updates on the realism bench's nuisances, per identification rate.

Usage: ``python bench/live_realism.py [--seeds 2] [--duration 90] [--window 30] [--span 10] [--rates 50 25]
[--only NAME ...]`` (with the worktree first on PYTHONPATH).

For every nuisance of ``bench/realism.py`` (its sessions without a tare: the live node tares from its own recording)
and seed, a 3-segment human-arm session is simulated at the node's rates (1 kHz wrench, 100 Hz markers), its markers
go through the live causal angle estimator, and the stream is fed to :class:`WindowedIdentifier` (``--window`` s,
body mass and height given, as the realism bench) as the node feeds it. Over the last ``--span`` s, one update every
0.2 s (the node's 5 Hz, the model checks at their live cadence) is scored against the simulated truth, once per
wrench rate in ``--rates`` (``WindowConfig.max_rate_hz``: the rate the window's wrench is block-averaged to).

Per nuisance and rate: updates valid, both error rates over the updates (valid with some |z| > 3: "v&wrong";
invalid with every |z| <= 3: "inv&right"), the worst |z| of a valid update, and the mean compute time per update
(ms, in process, one thread). The totals close the table. Updates 0.2 s apart share most of their samples: the
rates count updates, not independent sessions.
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
from realism import _NUMBER, NUISANCES
from scoring import rates, verdict, z_scores

from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.pipeline import IdentifyOptions
from bsp_ros.core.simulation import human_arm_cell
from bsp_ros.live.online.windowed import WindowConfig, WindowedIdentifier, WindowEstimate

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "test" / "bsp_ros" / "live" / "online"))

PERIOD_S = 0.2  # the identifier's default 5 Hz


def _updates(
    inputs, rate_hz: float, window_s: float, span_s: float
) -> tuple[list[bool], list[float], list[float], list[str]]:
    """Feed one session's live inputs and identify every 0.2 s over its last ``span_s`` s: (valid, worst |z|, ms,
    the invalid updates' messages)."""
    simulated, stamps, wrench, _, raw = inputs
    truth = simulated.truth.to_dict()
    session = simulated.session
    rotation = np.asarray(session.rotation_world_from_sensor, dtype=np.float64)
    rotation = rotation if rotation.ndim == 2 else rotation[-1]
    frame_id = session.wrench.frame_id
    # As the node's (bsp_identifier): the passive model as named, a missing elastic moment a verdict, not a refit.
    options = IdentifyOptions(subject=SubjectInfo(75.0, 1.78, "male"), elastic_fallback=False)
    identifier = WindowedIdentifier(3, WindowConfig(window_s=window_s, options=options, max_rate_hz=rate_hz))
    end_ns = int(stamps[-1])
    first_ns = end_ns - int(span_s * 1e9)
    wrench_i = angle_i = 0
    valid, worst, ms, messages = [], [], [], []
    for k in range(round(span_s / PERIOD_S) + 1):
        t_ns = first_ns + int(k * PERIOD_S * 1e9)
        while angle_i < len(raw) and raw[angle_i][0] <= t_ns:
            identifier.add_joint_state(raw[angle_i][0], raw[angle_i][1], raw[angle_i][2])
            angle_i += 1
        while wrench_i < len(stamps) and stamps[wrench_i] <= t_ns:
            identifier.add_wrench(int(stamps[wrench_i]), wrench[wrench_i])
            wrench_i += 1
        started = time.perf_counter()
        window = identifier.snapshot()
        if not isinstance(window, WindowEstimate):
            # As the node: the wrench's orientation rides with the window, for the sensor zero's share of the std.
            window = dataclasses.replace(window, rotation_world_from_sensor=rotation, wrench_frame_id=frame_id)
            window = identifier.estimate_window(window)
        estimate = window
        ms.append(1e3 * (time.perf_counter() - started))
        valid.append(bool(estimate.valid))
        worst.append(max(z_scores(estimate.document, truth).values(), default=float("nan")))
        if not estimate.valid:
            messages.append(_NUMBER.sub("#", str(estimate.document["quality"].get("message", "")))[:70])
    return valid, worst, ms, messages


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--duration", type=float, default=90.0, help="session length, s")
    parser.add_argument("--window", type=float, default=30.0, help="the identifier's window, s")
    parser.add_argument("--span", type=float, default=10.0, help="the session's last seconds scored, s")
    parser.add_argument("--rates", type=float, nargs="+", default=[50.0, 25.0], help="max_rate_hz values")
    parser.add_argument("--only", nargs="+", metavar="NAME", help="nuisances whose name contains one of these")
    args = parser.parse_args(argv)
    from live_inputs import live_inputs  # the live tests' simulated inputs (test/bsp_ros/live/online)

    names = [n for n in NUISANCES if not args.only or any(o.lower() in n.lower() for o in args.only)]
    header = (
        f"{'nuisance':28s} {'Hz':>4s} {'valid':>8s} {'v&wrong':>7s} {'inv&right':>9s} {'worst|z|':>8s} {'ms':>5s}"
        "  most frequent invalid message"
    )
    print(header)
    print("-" * len(header))
    totals: dict[float, list[str]] = {rate: [] for rate in args.rates}
    times: dict[float, list[float]] = {rate: [] for rate in args.rates}
    started = time.perf_counter()
    for name in names:
        sessions = []
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            spec = NUISANCES[name](human_arm_cell(duration_s=args.duration, seed=seed), seed)
            spec = dataclasses.replace(
                spec,
                sensor=dataclasses.replace(spec.sensor, wrench_hz=1000.0),
                markers=dataclasses.replace(spec.markers, marker_hz=100.0),
            )
            sessions.append(live_inputs(spec))
        for rate in args.rates:
            valid, worst, ms, messages = [], [], [], []
            for inputs in sessions:
                v, z, t, m = _updates(inputs, rate, args.window, args.span)
                valid += v
                worst += z
                ms += t
                messages += m
            verdicts = [verdict(v, z) for v, z in zip(valid, worst, strict=True)]
            totals[rate] += verdicts
            times[rate] += ms
            _, wrong, thrown = rates(verdicts)
            worst_valid = max((z for v, z in zip(valid, worst, strict=True) if v), default=float("nan"))
            print(
                f"{name:28s} {rate:4.0f} {sum(valid):>4d}/{len(valid):<3d} {wrong:>7d} {thrown:>9d} {worst_valid:8.2f}"
                f" {np.mean(ms):5.1f}  {collections.Counter(messages).most_common(1)[0][0] if messages else '-'}",
                flush=True,
            )
    for rate in args.rates:
        total, wrong, thrown = rates(totals[rate])
        print(
            f"{rate:g} Hz: valid-and-wrong {wrong}/{total} updates ({100 * wrong / max(total, 1):.1f} %), "
            f"invalid-and-right {thrown}/{total} ({100 * thrown / max(total, 1):.1f} %), "
            f"compute mean {np.mean(times[rate]):.1f} ms, max {np.max(times[rate]):.1f} ms"
        )
    print(
        f"({len(names) * args.seeds} sessions in {time.perf_counter() - started:.0f} s; seeds {args.first_seed}..."
        f"{args.first_seed + args.seeds - 1}, {args.duration:g} s sessions, {args.window:g} s window, last "
        f"{args.span:g} s scored)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
