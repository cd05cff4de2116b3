"""The `bsp` command: the subcommands of COMMANDS, each a module of this package with `add_parser` and `run`."""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import sys
from collections.abc import Sequence

from bsp_ros import __version__
from bsp_ros.allocator import reuse_freed_memory
from bsp_ros.errors import BspError

# What a shell reports for a Unix tool killed by SIGPIPE (128 + 13): `bsp ... | head -1` stops quietly with it.
EXIT_BROKEN_PIPE = 141
EXIT_INTERRUPTED = 130

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
    "watch",
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
    """Run `bsp`; return the process exit code (a BspError's `exit_code` on a handled failure).

    One place for what every command shares: a BspError is one `bsp <command>: error: ...` line; Ctrl-C is
    `bsp <command>: interrupted` and 130; a reader that stopped reading (`bsp ... | head -1`) ends the command
    quietly with 141, as SIGPIPE ends a Unix tool (the signal itself stays ignored, as Python sets it, so the
    store's and the middleware's sockets keep their EPIPE errors).
    """
    words = list(sys.argv[1:] if argv is None else argv)
    # Named before the parser is built, so a Ctrl-C during start-up still says which command stopped.
    command = next((f"bsp {word}" for word in words if not word.startswith("-")), "bsp")
    try:
        parser = build_parser()
        args = parser.parse_args(words)
        if not hasattr(args, "_run"):
            parser.print_help()
            sys.stdout.flush()
            return 2
        reuse_freed_memory()
        try:
            code = int(args._run(args) or 0)
        except BspError as error:
            print(f"{command}: error: {error}", file=sys.stderr)
            code = error.exit_code
        # Flushed here, not at interpreter exit, so a reader that went away is seen by the handler below.
        sys.stdout.flush()
        return code
    except KeyboardInterrupt:
        _say(f"{command}: interrupted")
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        _silence_stdout()
        return EXIT_BROKEN_PIPE
    except OSError as error:
        if error.errno != errno.EPIPE:
            raise
        _silence_stdout()
        return EXIT_BROKEN_PIPE


def _say(line: str) -> None:
    try:
        print(line, file=sys.stderr, flush=True)
    except OSError:  # stderr closed as well: the exit code says it
        pass


def _silence_stdout() -> None:
    """Send what is left of stdout to /dev/null, so the interpreter's final flush does not fail again."""
    stream = sys.stdout
    try:
        fd = stream.fileno()
    except (AttributeError, OSError, ValueError):  # a replaced stream (a test's capture): drop its buffer only
        fd = -1
    if fd == 1 and stream is sys.__stdout__:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, fd)
        os.close(devnull)
    else:
        sys.stdout = open(os.devnull, "w")  # lives until the process ends
