"""Benchmark: start-up time of `bsp --version` and of every `bsp <cmd> --help`, against a bare interpreter.

Usage: ``python bench/bench_cli_startup.py [--repeat 15] [--target 0.3]``

Each run is a fresh ``python -m bsp_ros.cli ...`` subprocess (what the ``bsp`` script does, plus the runpy
step), timed from spawn to exit. Prints median and max wall time per command, the median's ratio to the
target, and the same for ``python -c pass`` in the same run so a loaded machine shows as a slow baseline
rather than a slow CLI. Runs are interleaved (command by command within each round) so load drifts hit all
commands alike. Exit code 1 if any command's median misses the target.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

from bsp_ros.cli import COMMANDS


def _time_once(argv: list[str]) -> float:
    start = time.perf_counter()
    done = subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, check=False)
    elapsed = time.perf_counter() - start
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(argv)} exited with {done.returncode}: {done.stderr.strip()[-400:]}")
    return elapsed


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=15, help="runs per command (default 15)")
    parser.add_argument("--target", type=float, default=0.3, help="start-up target in s (default 0.3)")
    args = parser.parse_args()

    cases: dict[str, list[str]] = {"python -c pass (baseline)": [sys.executable, "-c", "pass"]}
    cases["bsp --version"] = [sys.executable, "-m", "bsp_ros.cli", "--version"]
    for name in COMMANDS:
        cases[f"bsp {name} --help"] = [sys.executable, "-m", "bsp_ros.cli", name, "--help"]

    times: dict[str, list[float]] = {label: [] for label in cases}
    for argv in cases.values():  # warm the file cache (and .pyc files) once, untimed
        _time_once(argv)
    for _ in range(args.repeat):
        for label, argv in cases.items():
            times[label].append(_time_once(argv))

    baseline = statistics.median(times["python -c pass (baseline)"])
    print(f"{'command':28s} {'median s':>9s} {'max s':>7s} {'/target':>8s} {'- baseline s':>13s}")
    missed = []
    for label, values in times.items():
        median = statistics.median(values)
        print(f"{label:28s} {median:9.3f} {max(values):7.3f} {median / args.target:8.2f} {median - baseline:13.3f}")
        if label != "python -c pass (baseline)" and median >= args.target:
            missed.append(label)
    print(f"{args.repeat} runs each, target {args.target:g} s: " + (f"MISSED by {missed}" if missed else "all met"))
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
