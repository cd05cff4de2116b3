"""Whether a change to the estimator left `bsp identify`'s documents as they were, but for keys it added.

Run it once with the code before the change (``--write DIR``), once after (``--against DIR``)::

    python scripts/documents_unchanged.py BAG... --write /tmp/before      # on the old checkout
    python scripts/documents_unchanged.py BAG... --against /tmp/before    # on the new one

The second run prints one line per bag (``same``, or the first differing path) and exits 1 on any difference.
Numbers are compared to a relative 1e-9; keys present only in the new document are listed, not counted as a
difference; ``session.bsp_ros_version`` and the wall-clock timing keys are ignored.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

from bsp_ros.bag.offline import identify_bag
from bsp_ros.core.pipeline import IdentifyOptions

IGNORED = {"bsp_ros_version", "identified_ns", "elapsed_s"}


def differences(old: Any, new: Any, path: str = "") -> tuple[list[str], list[str]]:
    """Paths where ``new`` differs from ``old``, and paths of keys only ``new`` has."""
    if isinstance(old, dict) and isinstance(new, dict):
        changed: list[str] = []
        added = [f"{path}/{k}" for k in new if k not in old and k not in IGNORED]
        for key, value in old.items():
            if key in IGNORED:
                continue
            if key not in new:
                changed.append(f"{path}/{key} (removed)")
                continue
            more_changed, more_added = differences(value, new[key], f"{path}/{key}")
            changed += more_changed
            added += more_added
        return changed, added
    if isinstance(old, list) and isinstance(new, list):
        if len(old) != len(new):
            return [f"{path} (length {len(old)} -> {len(new)})"], []
        changed, added = [], []
        for k, (a, b) in enumerate(zip(old, new, strict=True)):
            more_changed, more_added = differences(a, b, f"{path}[{k}]")
            changed += more_changed
            added += more_added
        return changed, added
    if isinstance(old, float) and isinstance(new, float):
        same = math.isclose(old, new, rel_tol=1e-9, abs_tol=1e-12) or (math.isnan(old) and math.isnan(new))
        return ([] if same else [f"{path} ({old!r} -> {new!r})"]), []
    return ([] if old == new else [f"{path} ({old!r:.80} -> {new!r:.80})"]), []


def main(argv: list[str] | None = None) -> int:
    """Write the documents of the bags, or compare them with those written before; 1 on any difference."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("bags", nargs="+", type=Path)
    action = parser.add_mutually_exclusive_group(required=True)
    action.add_argument("--write", type=Path, metavar="DIR", help="write each bag's document into DIR")
    action.add_argument("--against", type=Path, metavar="DIR", help="compare with the documents in DIR")
    args = parser.parse_args(argv)
    failed = 0
    for bag in args.bags:
        document = json.loads(json.dumps(identify_bag(bag, IdentifyOptions())))
        name = f"{bag.name}.json"
        if args.write is not None:
            args.write.mkdir(parents=True, exist_ok=True)
            (args.write / name).write_text(json.dumps(document, indent=1, sort_keys=True))
            print(f"{bag.name}: written")
            continue
        before = json.loads((args.against / name).read_text())
        changed, added = differences(before, document)
        failed += bool(changed)
        print(f"{bag.name}: {'same' if not changed else 'DIFFERS at ' + '; '.join(changed[:3])}")
        if added:
            print(f"  added: {', '.join(sorted(set(added))[:8])}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
