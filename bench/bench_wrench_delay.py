"""Benchmark: the wrench-marker delay estimate over seeds: its calibration (rms of z) and its cost against identify.

Usage: ``python bench/bench_wrench_delay.py [--seeds 14] [--duration 60] [--delay-ms 20] [--filter-ms 1.5]``

Each seed simulates a human-arm session whose wrench is ``--delay-ms`` late and averaged over ``--filter-ms``
(the test's construction, test/bsp_ros/core/identification/test_timing.py), estimates the delay, and prints
the error in std; the rms of those z should be about 1 for an honest std. The cost is the estimate's wall
time beside `identify_session`'s with the delay given (no estimate).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "test" / "bsp_ros" / "core" / "identification"))
from test_timing import delayed_session

from bsp_ros.core.identification.timing import delay_problem, estimate_wrench_delay
from bsp_ros.core.pipeline import IdentifyOptions, identify_session


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=14)
    parser.add_argument("--duration", type=float, default=60.0)
    parser.add_argument("--delay-ms", type=float, default=20.0)
    parser.add_argument("--filter-ms", type=float, default=1.5)
    args = parser.parse_args()
    truth_s = (args.delay_ms + args.filter_ms / 2) / 1e3
    z, cost, identify = [], [], []
    for seed in range(args.seeds):
        session, _ = delayed_session(seed, args.delay_ms / 1e3, args.filter_ms / 1e3, args.duration)
        started = time.perf_counter()
        delay = estimate_wrench_delay(delay_problem(session))
        cost.append(time.perf_counter() - started)
        started = time.perf_counter()
        identify_session(session, IdentifyOptions(wrench_delay_s=truth_s))
        identify.append(time.perf_counter() - started)
        z.append((delay.estimate_s - truth_s) / delay.estimate_std_s)
        print(
            f"seed {seed}: {1e3 * delay.estimate_s:.2f} +- {1e3 * delay.estimate_std_s:.2f} ms "
            f"(truth {1e3 * truth_s:.2f}), z {z[-1]:+.2f}, {delay.source}, {delay.n_fits} fits, {cost[-1]:.3f} s",
            flush=True,
        )
    print(
        f"rms z {np.sqrt(np.mean(np.square(z))):.2f} over {len(z)} seeds; estimate {np.median(cost):.3f} s median "
        f"against identify_session {np.median(identify):.3f} s"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
