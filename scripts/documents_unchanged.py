"""Whether a change to the estimator left `bsp identify`'s documents as they were, but for keys it added.

A refactor of the core should not change its answers. This script makes that claim checkable: a fixed manifest of
varied bags (simulated sessions of several arms and settings, the sample bags under ``bags/``, two MuJoCo sessions),
each re-created from its seed; ``bsp identify`` run on each with the tree of a given revision (a git worktree); and
the two revisions' documents diffed. Numbers may differ by a relative ``--rel-tol`` (default 1e-9, with 1e-12
absolute for values near zero): summation order changes the last digits, an answer does not. A key only the newer
document has is a difference unless it is listed (``--allow-added``); ``software.version`` is not compared.

The whole check, from nothing (bags, both revisions' documents, the report, all under OUT)::

    python scripts/documents_unchanged.py revisions main HEAD --out /tmp/unchanged

Its steps, one by one::

    python scripts/documents_unchanged.py bags /tmp/unchanged/bags
    python scripts/documents_unchanged.py write /tmp/unchanged/main --bags /tmp/unchanged/bags --rev main
    python scripts/documents_unchanged.py write /tmp/unchanged/new --bags /tmp/unchanged/bags --rev .
    python scripts/documents_unchanged.py compare /tmp/unchanged/main /tmp/unchanged/new --allow-added '*/budget'

``--rev`` takes a git revision (checked out as a detached worktree beside the repository's and removed after) or
``.`` for the working tree as it is. ``compare`` and ``revisions`` print one line per bag (``same``, or the
first differing paths) and exit 1 on any difference; a bag that one revision cannot identify at all is one.
"""

from __future__ import annotations

import argparse
import contextlib
import fnmatch
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
REL_TOL = 1e-9
ABS_TOL = 1e-12
# Paths never compared: the package version changes with a release, not with an answer.
IGNORED = ("/software/version",)


class Kind(StrEnum):
    """How a manifest bag is made."""

    SIMULATE = "simulate"
    SAMPLE = "sample"
    MUJOCO = "mujoco"


@dataclass(frozen=True, kw_only=True)
class Case:
    """One bag of the manifest and how it is identified.

    Attributes
    ----------
    name : the bag's directory name and its document's stem.
    kind : :class:`Kind` value.
    make : ``bsp simulate`` options (SIMULATE), the folder under ``bags/`` (SAMPLE), or
        ``(seed, sensor, springs)`` as strings (MUJOCO).
    identify : extra ``bsp identify`` options.
    """

    name: str
    kind: Kind
    make: tuple[str, ...]
    identify: tuple[str, ...] = ()


def _sim(name: str, seed: int, options: str, identify: str = "") -> Case:
    return Case(
        name=name, kind=Kind.SIMULATE, make=("--seed", str(seed), *options.split()), identify=tuple(identify.split())
    )


FEMALE = "--sex female --body-mass 62 --height 1.66"

# Each case exercises another path of the estimator; every bag is made from its seed, so the set is the same on
# every machine. Durations are short (3-40 s) to keep a run of both revisions within a few minutes.
MANIFEST: tuple[Case, ...] = (
    _sim("sim_human", 11, "--duration 40", identify="--body-mass 75 --height 1.78"),
    _sim("sim_paper_arm", 12, "--subject paper-arm --duration 40"),
    _sim("sim_paper_method", 12, "--subject paper-arm --duration 40", identify="--method paper"),
    _sim("sim_female_occluded", 13, f"--duration 40 --dropout 0.05 {FEMALE}", identify=FEMALE),
    _sim("sim_springs_auto", 14, "--duration 40 --stiffness 0.4 0.8 0.1", identify="--passive auto"),
    _sim("sim_offset_drift", 15, "--duration 40 --force-offset 1.0 -0.5 2.0 --force-drift 0.01 0 0"),
    _sim("sim_fast_inertia", 16, "--duration 30 --inertia --speed-scale 4 --wrench-hz 500"),
    _sim("sim_spikes_skin", 17, "--duration 40 --spikes 0.002 --skin-offset-mm 2"),
    _sim("sim_robot_turning", 18, "--duration 40 --robot-handle-pose --sensor-turns"),
    _sim("sim_short", 19, "--duration 3"),
    _sim("sim_no_tf", 20, "--duration 30 --no-tf-static"),
    _sim("sim_stribeck_delay", 21, "--duration 40 --stribeck-ratio 1.5 --wrench-filter-delay-s 0.02"),
    Case(name="human_arm_60s", kind=Kind.SAMPLE, make=("human_arm_60s",)),
    Case(name="paper_arm_60s", kind=Kind.SAMPLE, make=("paper_arm_60s",)),
    Case(
        name="human_arm_occluded_60s",
        kind=Kind.SAMPLE,
        make=("human_arm_occluded_60s",),
        identify=tuple(FEMALE.split()),
    ),
    Case(name="mujoco_fixed", kind=Kind.MUJOCO, make=("2", "fixed", "")),
    Case(
        name="mujoco_turning_springs",
        kind=Kind.MUJOCO,
        make=("4", "turning", "springs"),
        identify=("--passive", "auto"),
    ),
)


@dataclass(frozen=True, kw_only=True)
class Comparison:
    """What differs between two documents.

    Attributes
    ----------
    changed : paths whose value changed or that the newer document lacks, each with the two values.
    added : paths only the newer document has and no ``allowed_added`` pattern names (a difference).
    allowed : paths only the newer document has that a pattern names (listed, not a difference).
    """

    changed: tuple[str, ...] = ()
    added: tuple[str, ...] = ()
    allowed: tuple[str, ...] = ()

    @property
    def equal(self) -> bool:
        """True when nothing changed and every added key is an allowed one."""
        return not self.changed and not self.added

    def __add__(self, other: Comparison) -> Comparison:
        return Comparison(
            changed=self.changed + other.changed, added=self.added + other.added, allowed=self.allowed + other.allowed
        )


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _numbers_close(old: float, new: float, rel_tol: float) -> bool:
    if math.isnan(old) or math.isnan(new):
        return math.isnan(old) and math.isnan(new)
    return math.isclose(old, new, rel_tol=rel_tol, abs_tol=ABS_TOL)


def _allowed(path: str, patterns: Sequence[str]) -> bool:
    """A pattern with a ``/`` matches the whole path (fnmatch); a bare name matches the path's last key."""
    last = path.rsplit("/", 1)[-1]
    return any(fnmatch.fnmatchcase(path if "/" in p else last, p) for p in patterns)


def compare_documents(
    old: Any, new: Any, *, rel_tol: float = REL_TOL, allowed_added: Sequence[str] = (), path: str = ""
) -> Comparison:
    """Compare two JSON documents (``bsp identify --json``), the older first.

    Parameters
    ----------
    old, new : the parsed documents (dicts, lists, strings, numbers, None).
    rel_tol : relative tolerance on numbers (1 = 100 %); below ``ABS_TOL`` in absolute value they are equal too.
    allowed_added : patterns of keys the newer document may add (``'*/budget'``, or a bare key name).
    path : the path of ``old`` and ``new`` in their documents (``/segments/hand``); "" at the top.

    Returns
    -------
    Comparison
        The changed, added and allowed-added paths; lists are compared element by element.
    """
    if path in IGNORED:
        return Comparison()
    if isinstance(old, dict) and isinstance(new, dict):
        result = Comparison()
        for key in new.keys() - old.keys():
            sub = f"{path}/{key}"
            if sub not in IGNORED:
                listed = _allowed(sub, allowed_added)
                result += Comparison(added=() if listed else (sub,), allowed=(sub,) if listed else ())
        for key, value in old.items():
            sub = f"{path}/{key}"
            if key not in new:
                result += Comparison(changed=() if sub in IGNORED else (f"{sub} (removed)",))
            else:
                result += compare_documents(value, new[key], rel_tol=rel_tol, allowed_added=allowed_added, path=sub)
        return result
    if isinstance(old, list) and isinstance(new, list):
        if len(old) != len(new):
            return Comparison(changed=(f"{path} (length {len(old)} -> {len(new)})",))
        result = Comparison()
        for k, (a, b) in enumerate(zip(old, new, strict=True)):
            result += compare_documents(a, b, rel_tol=rel_tol, allowed_added=allowed_added, path=f"{path}[{k}]")
        return result
    if _is_number(old) and _is_number(new):
        same = _numbers_close(float(old), float(new), rel_tol)
    else:
        same = type(old) is type(new) and old == new
    return Comparison() if same else Comparison(changed=(f"{path} ({old!r:.80} -> {new!r:.80})",))


def _write_mujoco_bag(case: Case, out: Path) -> None:
    """A 40 s paper-sine session of a seeded MuJoCo arm (``test/physics``), 250 Hz wrench, seed = the arm's."""
    sys.path.insert(0, str(REPO / "test" / "physics"))
    from mujoco_bag import record, write_bag  # test helpers, needed only for these cases
    from mujoco_cell import CellOptions, draw_arm, paper_sine

    seed, sensor, springs = int(case.make[0]), case.make[1], case.make[2] == "springs"
    options = CellOptions(trajectory=paper_sine(0.03), duration_s=40.0, wrench_hz=250.0, sensor=sensor, seed=seed)
    write_bag(out, record(draw_arm(seed, springs=springs), options))


def make_bag(case: Case, bags_dir: Path) -> Path:
    """(Re)create one manifest bag under ``bags_dir`` (replacing what is there) and return its folder."""
    out = bags_dir / case.name
    if out.exists():
        shutil.rmtree(out)
    if case.kind == Kind.SAMPLE:
        shutil.copytree(REPO / "bags" / case.make[0], out)
    elif case.kind == Kind.SIMULATE:
        command = [sys.executable, "-m", "bsp_ros.cli", "simulate", "--out", str(out), *case.make]
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL, cwd=REPO)
    else:
        _write_mujoco_bag(case, out)
    return out


@contextlib.contextmanager
def revision_tree(rev: str) -> Iterator[Path]:
    """The source tree of ``rev``: the working tree for ``.``, else a detached git worktree removed afterwards."""
    if rev == ".":
        yield REPO
        return
    parent = Path(tempfile.mkdtemp(prefix="documents_unchanged_"))
    tree = parent / "tree"
    git = ["git", "-C", str(REPO)]
    subprocess.run([*git, "worktree", "add", "--detach", "--quiet", str(tree), rev], check=True)
    try:
        yield tree
    finally:
        subprocess.run([*git, "worktree", "remove", "--force", str(tree)], check=False)
        shutil.rmtree(parent, ignore_errors=True)


def identify_with(tree: Path, bag: Path, out: Path, options: Sequence[str]) -> int:
    """Run ``bsp identify BAG --json OUT`` on ``tree``'s sources (first on PYTHONPATH) and return its exit code."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(tree), os.environ.get("PYTHONPATH")]))}
    command = [sys.executable, "-m", "bsp_ros.cli", "identify", str(bag), "--json", str(out), "--format", "none"]
    done = subprocess.run([*command, *options], env=env, cwd=tree, capture_output=True, text=True, check=False)
    if not out.exists():
        out.write_text(json.dumps({"failed": {"exit_code": done.returncode, "stderr": done.stderr.strip()[-400:]}}))
    return done.returncode


def write_documents(rev: str, bags_dir: Path, out_dir: Path) -> None:
    """Identify every manifest bag with ``rev``'s tree; each document into ``out_dir/<case>.json``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    with revision_tree(rev) as tree:
        head = subprocess.run(["git", "-C", str(tree), "rev-parse", "HEAD"], capture_output=True, text=True)
        (out_dir / "REVISION").write_text(f"{rev} {head.stdout.strip()}\n")
        for case in MANIFEST:
            code = identify_with(tree, bags_dir / case.name, out_dir / f"{case.name}.json", case.identify)
            print(f"{case.name}: exit {code}", flush=True)


def compare_dirs(old_dir: Path, new_dir: Path, *, rel_tol: float, allowed_added: Sequence[str]) -> int:
    """Print one line per manifest bag and return the number of bags whose documents differ."""
    differing = 0
    for case in MANIFEST:
        old = json.loads((old_dir / f"{case.name}.json").read_text())
        new = json.loads((new_dir / f"{case.name}.json").read_text())
        comparison = compare_documents(old, new, rel_tol=rel_tol, allowed_added=allowed_added)
        differing += not comparison.equal
        found = list(comparison.changed) + [f"{p} (added)" for p in comparison.added]
        print(f"{case.name}: {'same' if comparison.equal else 'DIFFERS at ' + '; '.join(found[:4])}")
        if comparison.allowed:
            print(f"  allowed added: {', '.join(sorted(set(comparison.allowed))[:8])}")
    print(f"{len(MANIFEST) - differing} of {len(MANIFEST)} bags the same (relative tolerance {rel_tol:g})")
    return differing


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    sub = parser.add_subparsers(dest="action", required=True)
    bags = sub.add_parser("bags", help="(re)create the manifest's bags in DIR")
    bags.add_argument("dir", type=Path)
    write = sub.add_parser("write", help="identify every bag with a revision's tree")
    write.add_argument("dir", type=Path)
    write.add_argument("--bags", type=Path, required=True, metavar="DIR")
    write.add_argument("--rev", default=".", help="git revision, or '.' for the working tree (default)")
    compare = sub.add_parser("compare", help="compare two revisions' documents")
    compare.add_argument("old", type=Path)
    compare.add_argument("new", type=Path)
    revisions = sub.add_parser("revisions", help="bags, both revisions' documents and their comparison")
    revisions.add_argument("old_rev")
    revisions.add_argument("new_rev", nargs="?", default=".")
    revisions.add_argument("--out", type=Path, required=True, metavar="DIR")
    revisions.add_argument("--keep-bags", action="store_true", help="reuse the bags already in OUT/bags")
    for p in (compare, revisions):
        p.add_argument("--rel-tol", type=float, default=REL_TOL, help=f"relative tolerance (default {REL_TOL:g})")
        what = "a key the newer revision may add ('*/budget', or a bare key name); repeatable"
        p.add_argument("--allow-added", action="append", default=[], metavar="PATTERN", help=what)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run one action; 1 when documents differ, 2 on a usage error."""
    args = _parser().parse_args(argv)
    if args.action == "bags":
        for case in MANIFEST:
            print(f"{make_bag(case, args.dir)}", flush=True)
        return 0
    if args.action == "write":
        write_documents(args.rev, args.bags, args.dir)
        return 0
    if args.action == "compare":
        return 1 if compare_dirs(args.old, args.new, rel_tol=args.rel_tol, allowed_added=args.allow_added) else 0
    bags_dir, old_dir, new_dir = args.out / "bags", args.out / "old", args.out / "new"
    if not (args.keep_bags and bags_dir.is_dir()):
        for case in MANIFEST:
            make_bag(case, bags_dir)
    write_documents(args.old_rev, bags_dir, old_dir)
    write_documents(args.new_rev, bags_dir, new_dir)
    return 1 if compare_dirs(old_dir, new_dir, rel_tol=args.rel_tol, allowed_added=args.allow_added) else 0


if __name__ == "__main__":
    sys.exit(main())
