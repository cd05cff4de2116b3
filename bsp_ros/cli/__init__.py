"""The `bsp` command: the subcommands of COMMANDS, each a module of this package with `add_parser` and `run`."""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from bsp_ros import __version__
from bsp_ros.errors import BspError

# One line per subcommand: the module `bsp_ros.cli.<name>`. A subcommand module imports only light modules at
# import time (its parser is built on every `bsp` start); numpy, scipy, matplotlib, rosbags and rclpy are
# imported inside its `run`, so `bsp --version` and `bsp <cmd> --help` stay fast (bench/bench_cli_startup.py).
COMMANDS: tuple[str, ...] = (
    "demo",
    "identify",
    "plan",
    "play",
    "record",
    "report",
    "sessions",
    "simulate",
    "subjects",
    "tare",
)


def build_parser() -> argparse.ArgumentParser:
    """The `bsp` argument parser with every subcommand registered."""
    parser = argparse.ArgumentParser(
        prog="bsp", description="Identify arm body segment parameters and passive joint moments."
    )
    parser.add_argument("--version", action="version", version=f"bsp_ros {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMANDS:
        module = importlib.import_module(f"{__name__}.{name}")
        sub = module.add_parser(subparsers)
        sub.set_defaults(_run=module.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run `bsp`; return the process exit code (a BspError's `exit_code` on a handled failure)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "_run"):
        parser.print_help()
        return 2
    try:
        return int(args._run(args) or 0)
    except BspError as error:
        print(f"bsp {args.command}: error: {error}", file=sys.stderr)
        return error.exit_code
    except KeyboardInterrupt:
        return 130
