"""`bsp identify --each` over many bags: bags per second and peak memory, one and two workers, against a shell loop.

Builds (once; reused from CACHE after) ``--bags`` simulated bags of mixed lengths (20-180 s), every tenth cut to
half its size and every 25th cut inside its first record, then runs, each in a fresh process:

- ``bsp identify --each CACHE/bags/* --json-dir ... --summary ... --jobs 1`` (and ``--jobs 2``);
- the shell loop a researcher would write otherwise: ``for b in ...; do bsp identify "$b" --json ...; done``.

Each prints its wall time, bags per second and memory: the peak resident set summed over the run's processes at
once (sampled every 20 ms from /proc, or psutil where installed: the main process, the forkserver and the
workers together) and the largest single process (the same sampling, and ``getrusage(RUSAGE_CHILDREN)`` of a
wrapper as a cross-check; the forkserver's workers are not its waited children, so it sees the main process only).
The two summaries must be equal, each run's JSON directory must hold one estimate per summary row with an estimate
(its ``json`` cell naming it), and the loop's exit codes must be those of the summary's rows; the bench exits 1
otherwise.

    PYTHONPATH=. nice -n 10 python bench/bench_identify_each.py /tmp/each-cache --bags 200
"""

from __future__ import annotations

import argparse
import contextlib
import csv
import io
import os
import shutil
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

DURATIONS_S = (20, 40, 60, 120, 180)
READY = ".bench-ready"  # written last into a bag: a bag without it was left half-built and is built again
WRAPPER = (
    "import resource, subprocess, sys\n"
    "code = subprocess.run(sys.argv[1:]).returncode\n"
    "print(f'maxrss_kb={resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss}', file=sys.stderr)\n"
    "sys.exit(code)\n"
)
LOOP = 'for b in "$@"; do bsp identify "$b" --json "$OUT/$(basename "$b").json" --format none 2>/dev/null; '
LOOP += 'echo "$b,$?" >> "$OUT/codes.csv"; done'


@dataclass
class Run:
    """One measured command: wall time (s), peaks (MiB), its exit code (None for the loop: bash's is its last echo)."""

    label: str
    bags: int
    wall_s: float
    tree_peak_mib: float
    process_peak_mib: float
    rusage_children_mib: float
    exit_code: int | None


def build_bags(cache: Path, count: int) -> Path:
    """``count`` bags under ``cache/bags`` (``b000``...), built where missing; returns the folder."""
    from bsp_ros.cli import main

    folder = cache / "bags"
    folder.mkdir(parents=True, exist_ok=True)
    for k in range(count):
        bag = folder / f"b{k:03d}"
        if (bag / READY).exists():
            continue
        shutil.rmtree(bag, ignore_errors=True)
        argv = ["simulate", "--out", str(bag), "--duration", str(DURATIONS_S[k % len(DURATIONS_S)]), "--seed", str(k)]
        with contextlib.redirect_stdout(io.StringIO()):
            if main(argv) != 0:
                raise SystemExit(f"bsp {' '.join(argv)} failed")
        (mcap,) = bag.glob("*.mcap")
        if k % 10 == 7:  # half the file lost: the intact part may still identify the arm
            os.truncate(mcap, mcap.stat().st_size // 2)
        elif k % 25 == 11:  # cut inside its first record: nothing survives
            os.truncate(mcap, 3000)
        (bag / READY).write_text("")
    return folder


def _rss_by_pid() -> dict[int, tuple[int, int]]:
    """pid -> (parent pid, resident set in KiB) of every process /proc shows."""
    out: dict[int, tuple[int, int]] = {}
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            status = Path(entry.path, "status").read_text()
        except OSError:  # ended meanwhile
            continue
        fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
        rss = fields.get("VmRSS", "0 kB").split()[0]
        out[int(entry.name)] = (int(fields.get("PPid", "0").strip()), int(rss))
    return out


def _tree_rss_kib(root: int) -> tuple[int, int]:
    """(summed, largest) resident set (KiB) of ``root``'s descendants (the measured command's processes, without
    the wrapper ``root`` itself)."""
    try:
        import psutil
    except ImportError:
        psutil = None
    if psutil is not None:
        try:
            procs = psutil.Process(root).children(recursive=True)
            sizes = [p.memory_info().rss // 1024 for p in procs]
        except psutil.Error:
            return 0, 0
        return sum(sizes), max(sizes, default=0)
    table = _rss_by_pid()
    tree, frontier = {root}, [root]
    while frontier:
        parent = frontier.pop()
        children = [pid for pid, (ppid, _) in table.items() if ppid == parent and pid not in tree]
        tree.update(children)
        frontier.extend(children)
    sizes = [table[pid][1] for pid in tree - {root} if pid in table]
    return sum(sizes), max(sizes, default=0)


def measure(label: str, bags: int, argv: list[str], env: dict[str, str] | None = None) -> Run:
    """Run ``argv`` under the rusage wrapper, sampling its process tree's memory until it ends."""
    started = time.perf_counter()
    process = subprocess.Popen(
        [sys.executable, "-c", WRAPPER, *argv], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=env
    )
    peaks = [0, 0]

    def sample() -> None:
        while process.poll() is None:
            summed, largest = _tree_rss_kib(process.pid)
            peaks[0], peaks[1] = max(peaks[0], summed), max(peaks[1], largest)
            time.sleep(0.02)

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    _, err = process.communicate()
    wall = time.perf_counter() - started
    sampler.join()
    maxrss = next((int(line.split("=")[1]) for line in err.splitlines() if line.startswith("maxrss_kb=")), 0)
    return Run(label, bags, wall, peaks[0] / 1024, peaks[1] / 1024, maxrss / 1024, process.returncode)


def _codes(summary: Path) -> dict[str, str]:
    with open(summary, newline="") as stream:
        return {Path(r["bag"]).name: r["exit_code"] for r in csv.DictReader(stream)}


def check_json_count(out: Path) -> str | None:
    """None when the run's JSON directory holds one estimate per summary row with an estimate (``valid`` given)
    and each such row names its file; else what differs."""
    with open(out / "summary.csv", newline="") as stream:
        rows = list(csv.DictReader(stream))
    estimated = [r for r in rows if r["valid"] != ""]
    files = sorted(p.name for p in (out / "json").glob("*.json"))
    named = sorted(r["json"] for r in estimated)
    if len(files) != len(estimated) or files != named:
        return f"{out.name}: {len(files)} JSON files, {len(estimated)} rows with an estimate naming {len(named)}"
    return None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("cache", type=Path, help="folder for the bags (reused) and the outputs")
    parser.add_argument("--bags", type=int, default=200, help="number of bags (default 200)")
    parser.add_argument("--no-loop", action="store_true", help="skip the shell loop (the slowest)")
    args = parser.parse_args()
    began = time.perf_counter()
    folder = build_bags(args.cache, args.bags)
    bags = sorted(p for p in folder.iterdir() if p.is_dir())[: args.bags]
    print(f"{len(bags)} bags in {folder} (built or checked in {time.perf_counter() - began:.0f} s)", flush=True)
    bsp = str(Path(sys.executable).with_name("bsp"))
    runs: list[Run] = []
    for jobs in (1, 2):
        out = args.cache / f"each-jobs{jobs}"
        shutil.rmtree(out, ignore_errors=True)
        argv = [bsp, "identify", "--each", *map(str, bags), "--json-dir", str(out / "json")]
        runs.append(
            measure(
                f"--each --jobs {jobs}", len(bags), [*argv, "--summary", str(out / "summary.csv"), "--jobs", str(jobs)]
            )
        )
    one, two = (args.cache / f"each-jobs{j}" / "summary.csv" for j in (1, 2))
    same = one.read_text() == two.read_text()
    json_failures = [f for f in (check_json_count(args.cache / f"each-jobs{j}") for j in (1, 2)) if f is not None]
    failed = json_failures + ([] if same else ["the summaries of --jobs 1 and --jobs 2 differ"])
    if not args.no_loop:
        out = args.cache / "loop"
        shutil.rmtree(out, ignore_errors=True)
        out.mkdir()
        env = {**os.environ, "OUT": str(out), "PATH": f"{Path(bsp).parent}{os.pathsep}{os.environ.get('PATH', '')}"}
        runs.append(measure("shell loop", len(bags), ["bash", "-c", LOOP, "loop", *map(str, bags)], env))
        runs[-1].exit_code = None
        with open(out / "codes.csv", newline="") as stream:
            loop_codes = {Path(bag).name: code for bag, code in csv.reader(stream)}
        print(f"the loop's exit codes equal the summary's: {loop_codes == _codes(one)}")
        failed += [] if loop_codes == _codes(one) else ["the loop's exit codes differ from the summary's"]
    codes = _codes(one)
    tally = {code: sum(c == code for c in codes.values()) for code in sorted(set(codes.values()), key=int)}
    print(f"summaries of --jobs 1 and --jobs 2 equal: {same}; exit codes per bag: {tally}")
    print(
        f"{'run':18s} {'bags':>5s} {'wall s':>8s} {'bags/s':>7s} {'tree peak MiB':>14s} {'proc peak MiB':>14s} "
        f"{'ru_maxrss MiB':>14s} {'exit':>5s}"
    )
    for run in runs:
        code = "-" if run.exit_code is None else str(run.exit_code)
        print(
            f"{run.label:18s} {run.bags:5d} {run.wall_s:8.1f} {run.bags / run.wall_s:7.2f} {run.tree_peak_mib:14.0f} "
            f"{run.process_peak_mib:14.0f} {run.rusage_children_mib:14.0f} {code:>5s}"
        )
    print(f"one JSON per row with an estimate, each named in its row: {not json_failures}")
    for failure in failed:
        print(f"FAILED: {failure}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
