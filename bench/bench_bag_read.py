"""Benchmark: read (+ identify) a 10-minute session bag with bsp_ros.bag vs rosbags AnyReader deserialising it.

Usage: ``python bench/bench_bag_read.py [--minutes 10] [--repeat 3] [--no-identify] [--keep DIR]``

Each measurement runs in a fresh Python process: wall time is the best of ``--repeat`` runs, peak memory
is the process's peak resident set size (``ru_maxrss``) above its size after the imports, and in a
second pass the peak of Python allocations (``tracemalloc``).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

_ROSBAGS = """
from pathlib import Path
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

def task(path):
    n = 0
    with AnyReader([Path(path)], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
        for connection, _, raw in reader.messages():
            reader.deserialize(raw, connection.msgtype)
            n += 1
    return n
"""

_OURS = """
from bsp_ros.bag import read_session

def task(path):
    if IDENTIFY:  # everything `bsp identify` does but printing: read, angles, identification, prior fusion
        from bsp_ros.bag.offline import identify_bag
        document = identify_bag(path)
        return sum(document["bag"]["messages"].values())
    result = read_session(path)
    return result.session.wrench.t_ns.size + sum(m.t_ns.size for m in result.session.markers.values())
"""

_HARNESS = """
import json, resource, sys, time, tracemalloc
IDENTIFY = {identify}
{body}
path, repeat, trace = sys.argv[1], int(sys.argv[2]), sys.argv[3] == "1"
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
if trace:
    tracemalloc.start()
    task(path)
    print(json.dumps({{"traced_peak_mb": tracemalloc.get_traced_memory()[1] / 2**20}}))
else:
    best, count = float("inf"), 0
    for _ in range(repeat):
        t0 = time.perf_counter()
        count = task(path)
        best = min(best, time.perf_counter() - t0)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(json.dumps({{"wall_s": best, "messages": count, "rss_peak_mb": peak / 1024,
                      "rss_growth_mb": (peak - base) / 1024}}))
"""


def _run(body: str, bag: Path, repeat: int, identify: bool, trace: bool) -> dict[str, float]:
    code = _HARNESS.format(body=body, identify=identify)
    out = subprocess.run(
        [sys.executable, "-c", code, str(bag), str(repeat), "1" if trace else "0"],
        check=True,
        capture_output=True,
        text=True,
    )
    return dict(json.loads(out.stdout.strip().splitlines()[-1]))


def main() -> int:
    """Write the session, time both readers, print the figures and the ratio."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--no-identify", action="store_true", help="time reading only")
    parser.add_argument("--keep", type=Path, help="write the bag here and keep it")
    args = parser.parse_args()

    from bsp_ros.bag import write_session_bag
    from bsp_ros.core.simulation import human_arm_cell, simulate_cell

    with tempfile.TemporaryDirectory() as tmp:
        bag = args.keep or Path(tmp) / "session"
        t0 = time.perf_counter()
        simulated = simulate_cell(human_arm_cell(duration_s=60.0 * args.minutes))
        write_session_bag(bag, simulated.session, simulated.truth.to_dict())
        size = sum(f.stat().st_size for f in bag.iterdir())
        print(f"bag: {bag} ({size / 2**20:.1f} MiB), simulated+written in {time.perf_counter() - t0:.2f} s")
        identify = not args.no_identify
        rosbags = _run(_ROSBAGS, bag, args.repeat, identify, trace=False)
        rosbags.update(_run(_ROSBAGS, bag, 1, identify, trace=True))
        ours = _run(_OURS, bag, args.repeat, identify, trace=False)
        ours.update(_run(_OURS, bag, 1, identify, trace=True))
    label = "bsp_ros read_session" + (" + identify" if identify else "")
    for name, row in (("rosbags AnyReader deserialize", rosbags), (label, ours)):
        print(
            f"{name:40s} {row['wall_s']:7.3f} s  {int(row['messages']):7d} msgs  "
            f"peak RSS {row['rss_peak_mb']:6.1f} MB (+{row['rss_growth_mb']:.1f})  "
            f"traced peak {row['traced_peak_mb']:6.1f} MB"
        )
    print(f"ratio ours / rosbags: {ours['wall_s'] / rosbags['wall_s']:.3f} (target <= 1.5)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
