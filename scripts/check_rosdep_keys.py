"""Check package.xml's dependency keys against a rosdistro checkout (Jazzy packages, rosdep keys for noble).

Usage: ``python scripts/check_rosdep_keys.py ROSDISTRO_DIR [--write test/data/rosdep_keys_noble.yaml]``

ROSDISTRO_DIR is a clone of https://github.com/ros/rosdistro. Each ``*_depend`` key of package.xml must be a
package released in ``jazzy/distribution.yaml`` or a rosdep key of ``rosdep/*.yaml`` with a rule for Ubuntu
(noble or all versions). ``--write`` records the resolutions as the snapshot test/test_packaging.py checks
without network access. Exit code 0: all keys resolve; 1: some do not (listed).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


def package_keys(package_xml: Path) -> list[str]:
    """Every dependency key named in a format-3 package.xml."""
    root = ET.parse(package_xml).getroot()
    tags = ("depend", "exec_depend", "build_depend", "build_export_depend", "test_depend", "buildtool_depend")
    return sorted({element.text.strip() for tag in tags for element in root.iter(tag) if element.text})


def resolve(rosdistro: Path, keys: list[str]) -> tuple[dict[str, str], list[str]]:
    """Map each key to how rosdep resolves it on Ubuntu noble for Jazzy; list the keys it cannot."""
    distribution = yaml.safe_load((rosdistro / "jazzy" / "distribution.yaml").read_text())
    released = {}
    for repo, info in distribution["repositories"].items():
        release = info.get("release") or {}
        for name in release.get("packages", [repo]):
            released[name] = repo
    rules: dict[str, object] = {}
    for path in sorted((rosdistro / "rosdep").glob("*.yaml")):
        rules.update(yaml.safe_load(path.read_text()) or {})
    resolved, missing = {}, []
    for key in keys:
        if key in released:
            resolved[key] = f"ros-jazzy-{key.replace('_', '-')} (jazzy package, repository {released[key]})"
            continue
        ubuntu = (rules.get(key) or {}).get("ubuntu") if isinstance(rules.get(key), dict) else None
        if isinstance(ubuntu, dict) and "noble" in ubuntu:
            ubuntu = ubuntu["noble"]
        if ubuntu is None:
            missing.append(key)
        elif isinstance(ubuntu, dict) and "pip" in ubuntu:
            resolved[key] = "pip: " + " ".join(ubuntu["pip"]["packages"])
        elif isinstance(ubuntu, dict) and "packages" in ubuntu:
            resolved[key] = "apt: " + " ".join(ubuntu["packages"])
        else:
            resolved[key] = "apt: " + " ".join(ubuntu) if isinstance(ubuntu, list) else str(ubuntu)
    return resolved, missing


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rosdistro", type=Path, help="a clone of github.com/ros/rosdistro")
    parser.add_argument("--write", type=Path, help="write the resolutions as a YAML snapshot")
    args = parser.parse_args()
    keys = package_keys(ROOT / "package.xml")
    resolved, missing = resolve(args.rosdistro, keys)
    for key, how in resolved.items():
        print(f"{key:28s} {how}")
    for key in missing:
        print(f"{key:28s} NOT FOUND for Ubuntu noble / Jazzy")
    if args.write and not missing:
        commit = subprocess.run(
            ["git", "-C", str(args.rosdistro), "rev-parse", "HEAD"], capture_output=True, text=True, check=False
        ).stdout.strip()
        snapshot = {"rosdistro_commit": commit or "unknown", "keys": resolved}
        args.write.write_text(
            "# Written by scripts/check_rosdep_keys.py from a rosdistro checkout; read by test/test_packaging.py.\n"
            + yaml.safe_dump(snapshot, sort_keys=True, width=200)
        )
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
