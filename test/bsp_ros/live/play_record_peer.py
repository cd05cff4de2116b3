"""Run `bsp play` or `bsp record` in a test process without importing the other subcommands (faster start)."""

from __future__ import annotations

import argparse
import sys

from bsp_ros.cli import play, record
from bsp_ros.errors import BspError

if __name__ == "__main__":
    parser = argparse.ArgumentParser(prog="bsp")
    subparsers = parser.add_subparsers(dest="command", required=True)
    for module in (play, record):
        module.add_parser(subparsers).set_defaults(_run=module.run)
    args = parser.parse_args()
    try:
        sys.exit(args._run(args))
    except BspError as error:
        print(f"bsp {args.command}: error: {error}", file=sys.stderr)
        sys.exit(error.exit_code)
