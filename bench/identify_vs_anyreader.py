"""Issue 23: `bsp identify BAG` against rosbags' AnyReader deserialising the same bag, each a whole process.

Usage: ``python bench/identify_vs_anyreader.py [--minutes 10] [--wrench-hz 100] [--marker-hz 50] [--repeat 5]
[--keep DIR]`` (with the worktree first on PYTHONPATH and its venv's ``bsp`` on PATH).

Two bags of one simulated session (`bsp simulate --duration 60*MINUTES`): the one `bsp simulate` writes, and
the same messages re-written by rosbags' own ``Writer`` (MCAP storage, rosbag2 version 9; a bag we did not
write, as users' bags are). Each command runs in a fresh process, timed from start to exit (imports included),
best of ``--repeat``:

- baseline: ``python -c`` opening the bag with ``rosbags.highlevel.AnyReader`` (the Jazzy typestore) and
  deserialising every message (``reader.deserialize(raw, connection.msgtype)``), nothing else;
- ours: ``bsp identify BAG --format none`` (reading, joint angles, identification with every model check, prior
  fusion; nothing printed);
- and ``bsp --version`` (the CLI's start-up).

Every command runs from compiled bytecode (the package is compiled first, PYTHONDONTWRITEBYTECODE unset), as
`pip install` leaves both packages.

The baseline and ours run in turns, ``--repeat`` times each (this machine's speed drifts between blocks of runs).

Printed: seconds per command and bag, and ours / baseline (issue 23's target: <= 0.5).
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "test" / "bsp_ros" / "bag"))

_ANYREADER = """
import sys
from pathlib import Path
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore
n = 0
with AnyReader([Path(sys.argv[1])], default_typestore=get_typestore(Stores.ROS2_JAZZY)) as reader:
    for connection, _, raw in reader.messages():
        reader.deserialize(raw, connection.msgtype)
        n += 1
print(n)
"""


# Both sides run from compiled bytecode, as `pip install` leaves a package (rosbags' came compiled; ours is
# compiled below): with PYTHONDONTWRITEBYTECODE set, as on some machines, every run of ours would compile its
# ~170 modules first (0.12 s here) and the comparison would not be fair.
_ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def _timed(command: list[str]) -> tuple[float, int]:
    """Wall time of one run of ``command`` (s), and its exit code."""
    started = time.perf_counter()
    code = subprocess.run(
        command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False, env=_ENV
    ).returncode
    return time.perf_counter() - started, code


def best_of(command: list[str], repeat: int) -> tuple[float, int]:
    """The shortest wall time of ``repeat`` runs of ``command`` (s), and its exit code."""
    runs = [_timed(command) for _ in range(repeat)]
    return min(t for t, _ in runs), runs[-1][1]


def best_of_alternating(first: list[str], second: list[str], repeat: int) -> tuple[float, float, int]:
    """The shortest wall times of ``repeat`` runs of each command, run in turns (s), and ``second``'s exit code.

    In turns, not one command's runs after the other's: this machine's speed drifts by 10-20 % over tens of
    seconds, and a drift between two blocks of runs would show as a difference of the commands."""
    a, b, code = [], [], 0
    for _ in range(repeat):
        a.append(_timed(first)[0])
        elapsed, code = _timed(second)
        b.append(elapsed)
    return min(a), min(b), code


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--wrench-hz", type=float, default=100.0)
    parser.add_argument("--marker-hz", type=float, default=50.0)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--keep", type=Path, help="write the bags here and keep them")
    args = parser.parse_args()
    from bag_layouts import write_rosbags

    bsp = [sys.executable, "-m", "bsp_ros.cli"]
    root = Path(__file__).resolve().parents[1]
    for package in ("bsp_ros", "msg_adapters"):
        subprocess.run([sys.executable, "-m", "compileall", "-q", str(root / package)], check=True, env=_ENV)
    work = args.keep or Path(tempfile.mkdtemp(prefix="bench_identify_"))
    work.mkdir(parents=True, exist_ok=True)
    ours = work / "ours"
    if not ours.exists():
        subprocess.run(
            [
                *bsp,
                "simulate",
                "--out",
                str(ours),
                "--duration",
                f"{60 * args.minutes:g}",
                "--wrench-hz",
                f"{args.wrench_hz:g}",
                "--marker-hz",
                f"{args.marker_hz:g}",
                "--seed",
                "0",
            ],
            check=True,
            stdout=subprocess.DEVNULL,
        )
    theirs = work / "rosbags_writer"
    if not theirs.exists():
        write_rosbags(ours, theirs)
    size_mb = sum(f.stat().st_size for f in ours.glob("*.mcap")) / 1e6
    rates = f"wrench {args.wrench_hz:g} Hz, markers {args.marker_hz:g} Hz"
    print(f"{args.minutes:g}-minute session, {rates}, {size_mb:.1f} MB")
    version, _ = best_of([*bsp, "--version"], args.repeat)
    print(f"bsp --version                          {version:7.3f} s")
    print(f"{'bag':16s} {'AnyReader deserialise':>22s} {'bsp identify':>13s} {'ratio':>6s}  exit")
    for name, bag in (("bsp simulate", ours), ("rosbags Writer", theirs)):
        baseline, identify, code = best_of_alternating(
            [sys.executable, "-c", _ANYREADER, str(bag)], [*bsp, "identify", str(bag), "--format", "none"], args.repeat
        )
        print(f"{name:16s} {baseline:20.3f} s {identify:11.3f} s {identify / baseline:6.2f}  {code}")
    if args.keep is None:
        shutil.rmtree(work)


if __name__ == "__main__":
    main()
