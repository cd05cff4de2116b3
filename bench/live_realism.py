"""Live realism benchmark: the live identifier's estimates on the realism bench's nuisances, both error rates.

Usage: ``python bench/live_realism.py [--seeds 3] [--duration 90] [--window 30] [--span 10] [--rates 50]
[--recursive] [--only NAME ...]`` (with the worktree first on PYTHONPATH).

For every nuisance of ``bench/realism.py`` (its sessions without a tare: the live node tares from its own recording)
and seed, a 3-segment human-arm session is simulated at the node's rates (1 kHz wrench, 100 Hz markers), its markers
go through the live causal angle estimator, and the stream is fed to :class:`WindowedIdentifier` (``--window`` s,
the node's options: the passive model as named, no elastic fallback; body mass and height given, as the realism
bench does) as ``bsp_identifier`` feeds it, the wrench sensor's orientation with each window. Over the last
``--span`` s, one update every 0.2 s (the node's 5 Hz from the stream's start, the model checks at their live cadence:
what the checks before the span found holds into it) is scored against the
simulated truth, once per wrench rate in ``--rates`` (``WindowConfig.max_rate_hz``: the rate the window's wrench is
block-averaged to). With ``--recursive`` the recursive mode as the node runs it (``live_inputs.recursive_mode``:
:class:`RecursiveFeed` on the causal joint states and every wrench, its window identified with every model check
every 10 s, the filter's 5 Hz estimate held to it) is scored at the same instants (rows "rec"); with
``--recursive-alone`` the filter's estimate without its window (rows "filt": the node before 2026-11-27).

Per nuisance and mode: updates valid, both error rates over the updates (valid with some |z| > 3: "v&wrong";
invalid with every |z| <= 3: "inv&right"), the worst |z| of a valid update, two-sided calibration over the
data-sourced parameters of the valid updates (``bench/calibration.py``: z RMS, 1 for an honest std; the shares within
1 and 2 std, 68 % and 95 % for an honest std) and the sharpness (per parameter the median std over the RMS error
across the valid updates of every seed, one arm re-simulated, 1 ideal; per kind, static moments "SM", Coulomb
amplitudes "C", masses "m", the median and range over its parameters), the mean compute time per update
(ms, in process, one thread; the recursive mode's: its estimate document only) and the most frequent cause of an
invalid one (its first invalid finding's code and where, ``bench/finding_kinds.py``). The totals close the table.
Updates 0.2 s apart share most of their samples: the rates count updates, not independent sessions (nor do they
give the sharpness more than one error per seed).
"""

from __future__ import annotations

import argparse
import collections
import dataclasses
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from calibration import calibration_columns, calibration_header, sharpness_columns, sharpness_header, summary_line
from finding_kinds import cause_of
from realism import NUISANCES
from scoring import Counts, Scored, residuals, scored

from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.pipeline import IdentifyOptions
from bsp_ros.core.simulation import human_arm_cell
from bsp_ros.live.online.windowed import WindowConfig, WindowedIdentifier

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "test" / "bsp_ros" / "live" / "online"))
from live_inputs import WindowFeed, live_inputs, orientation, recursive_mode  # the live tests' shared inputs

PERIOD_S = 0.2  # the identifier's default 5 Hz


def _updates(
    inputs: tuple[Any, ...], rate_hz: float, window_s: float, span_s: float, counts: Counts
) -> tuple[list[Scored], list[float], list[str]]:
    """Feed one session's live inputs and identify every 0.2 s over its last ``span_s`` s: (each update scored, ms,
    the invalid updates' causes); each update is counted in ``counts``."""
    simulated, stamps, wrench, _, raw = inputs
    truth = simulated.truth.to_dict()
    frame = orientation(simulated)
    identifier = WindowedIdentifier(3, WindowConfig(window_s=window_s, options=_node_options(), max_rate_hz=rate_hz))
    feed = WindowFeed(identifier, stamps, wrench, raw)
    first_ns = int(stamps[-1]) - int(span_s * 1e9)
    # As the node, from the stream's start: what the model checks before the scored span found holds into it.
    period_ns = int(PERIOD_S * 1e9)
    tick_ns = first_ns - (first_ns - int(stamps[0])) // period_ns * period_ns  # the first tick on the span's grid
    updates, ms, causes = [], [], []
    while tick_ns < first_ns:
        feed.until(tick_ns)
        identifier.estimate(orientation=frame)
        tick_ns += period_ns
    for k in range(round(span_s / PERIOD_S) + 1):
        feed.until(first_ns + int(k * PERIOD_S * 1e9))
        started = time.perf_counter()
        estimate = identifier.estimate(orientation=frame)  # as the node: the orientation rides with the window
        ms.append(1e3 * (time.perf_counter() - started))
        updates.append(counts.count(Scored.from_residuals(bool(estimate.valid), residuals(estimate.document, truth))))
        if not estimate.valid:
            causes.append(cause_of(estimate.document["quality"]))
    return updates, ms, causes


def _recursive_updates(
    inputs: tuple[Any, ...], window_s: float, span_s: float, counts: Counts, checked: bool = True
) -> tuple[list[Scored], list[float], list[str]]:
    """The recursive mode as the node runs it (``live_inputs.recursive_mode``), scored every 0.2 s over the last
    ``span_s`` s as :func:`_updates` scores the windowed one (the time: the estimate's, its window checks included;
    each update is counted in ``counts``)."""
    simulated, stamps = inputs[0], inputs[1]
    truth = simulated.truth.to_dict()
    from_ns = int(stamps[-1]) - int(span_s * 1e9)
    documents, seconds = recursive_mode(inputs, _node_options(), window_s, from_ns, checked)
    updates = [counts.count(scored(d, truth)) for d in documents]
    causes = [cause_of(d["quality"]) for d in documents if not d["quality"]["valid"]]
    return updates, [1e3 * t for t in seconds], causes


def _node_options() -> IdentifyOptions:
    """As the node's (bsp_identifier): the passive model as named, a missing elastic moment a verdict, not a refit;
    body mass and height given, as the realism bench does."""
    return IdentifyOptions(subject=SubjectInfo(75.0, 1.78, "male"), elastic_fallback=False)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--duration", type=float, default=90.0, help="session length, s")
    parser.add_argument("--window", type=float, default=30.0, help="the identifier's window, s")
    parser.add_argument("--span", type=float, default=10.0, help="the session's last seconds scored, s")
    parser.add_argument("--rates", type=float, nargs="+", default=[50.0], help="max_rate_hz values")
    parser.add_argument("--recursive", action="store_true", help="also score the recursive mode (rows 'rec')")
    parser.add_argument(
        "--recursive-alone",
        action="store_true",
        help="also score the recursive filter's estimate without its window's check (rows 'filt': before 2026-11-27)",
    )
    parser.add_argument("--only", nargs="+", metavar="NAME", help="nuisances whose name contains one of these")
    args = parser.parse_args(argv)

    names = [n for n in NUISANCES if not args.only or any(o.lower() in n.lower() for o in args.only)]
    header = (
        f"{'nuisance':28s} {'Hz':>4s} {'valid':>8s} {'v&wrong':>7s} {'inv&right':>9s} {'worst|z|':>8s}"
        f" {calibration_header()} {sharpness_header()} {'ms':>5s}  most frequent invalid cause"
    )
    print(header)
    print("-" * len(header))
    modes: list[float | str] = [
        *args.rates,
        *(["rec"] if args.recursive else []),
        *(["filt"] if args.recursive_alone else []),
    ]
    times: dict[float | str, list[float]] = {mode: [] for mode in modes}
    pooled: dict[float | str, Counts] = {mode: Counts() for mode in modes}
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
        for mode in modes:
            updates, ms, causes = [], [], []
            counts = Counts()
            for inputs in sessions:
                if mode in ("rec", "filt"):
                    u, t, m = _recursive_updates(inputs, args.window, args.span, counts, checked=mode == "rec")
                else:
                    u, t, m = _updates(inputs, float(mode), args.window, args.span, counts)
                updates += u
                ms += t
                causes += m
            times[mode] += ms
            pooled[mode].pool(counts)
            worst_valid = max((u.max_z for u in updates if u.valid), default=float("nan"))
            print(
                f"{name:28s} {mode:>4} {counts.valid:>4d}/{counts.runs:<3d} {counts.valid_wrong:>7d}"
                f" {counts.invalid_right:>9d} {worst_valid:8.2f} {calibration_columns(counts.two_sided.calibration())}"
                f" {sharpness_columns(counts.two_sided.sharpness())}"
                f" {np.mean(ms):5.1f}  {collections.Counter(causes).most_common(1)[0][0] if causes else '-'}",
                flush=True,
            )
    for mode in modes:
        total, wrong, thrown = pooled[mode].runs, pooled[mode].valid_wrong, pooled[mode].invalid_right
        label = {"rec": "recursive", "filt": "recursive filter alone"}.get(str(mode), f"windowed {mode} Hz")
        print(
            f"{label}: valid-and-wrong {wrong}/{total} updates ({100 * wrong / max(total, 1):.1f} %), "
            f"invalid-and-right {thrown}/{total} ({100 * thrown / max(total, 1):.1f} %), "
            f"compute mean {np.mean(times[mode]):.1f} ms, max {np.max(times[mode]):.1f} ms"
        )
        # No pooled sharpness: over nuisances one parameter's errors would mix them.
        print(summary_line(f"{label}, pooled over the valid updates", pooled[mode].two_sided, sharpness=False))
    print(
        f"({len(names) * args.seeds} sessions in {time.perf_counter() - started:.0f} s; seeds {args.first_seed}..."
        f"{args.first_seed + args.seeds - 1}, {args.duration:g} s sessions, {args.window:g} s window, last "
        f"{args.span:g} s scored)"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
