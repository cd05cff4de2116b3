"""Every `bsp` command ends like a Unix tool: quietly when its reader goes away (`| head`), named on Ctrl-C."""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

import bsp_ros.cli
from bsp_ros.cli import COMMANDS, EXIT_BROKEN_PIPE, EXIT_INTERRUPTED, main

ROOT = Path(__file__).resolve().parents[3]
PLAN = ["plan", "--shoulder", "0", "1.2", "--shoulder-range", "-70", "-10", "--elbow-range", "10", "100"]
PLAN += ["--wrist-range", "-20", "20", "--max-evaluations", "10"]


@pytest.fixture(scope="module")
def store(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """Short simulated bags and a store holding their estimates for three subjects (one recording each: the
    store refuses the same recording twice)."""
    root = tmp_path_factory.mktemp("pipes")
    store = root / "store.sqlite"
    for seed, subject in enumerate(("S01", "S02", "S03"), start=3):
        bag, result = root / f"session{seed}", root / f"e{seed}.json"
        assert main(["simulate", "--out", str(bag), "--duration", "10", "--seed", str(seed)]) == 0
        assert main(["identify", str(bag), "--json", str(result), "--format", "none"]) in (0, 1)
        assert main(["sessions", "add", str(result), "--subject", subject, "--store", str(store)]) == 0
    return root / "session3", store


def _bsp(argv: list[str], **kwargs: object) -> subprocess.Popen[bytes]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen(
        [sys.executable, "-m", "bsp_ros.cli", *argv],
        env=env,
        stderr=subprocess.PIPE,
        **kwargs,  # type: ignore[call-overload]
    )


@pytest.mark.parametrize("case", ["export", "show", "plan", "identify"])
def test_a_reader_that_goes_away_ends_the_command_quietly(case: str, store: tuple[Path, Path]) -> None:
    bag, path = store
    argv = {
        "export": ["sessions", "export", "--csv", "-", "--store", str(path)],
        "show": ["sessions", "show", "S01", "--json", "--store", str(path)],
        "plan": PLAN,
        "identify": ["identify", str(bag), "--format", "tsv"],
    }[case]
    process = _bsp(argv, stdout=subprocess.PIPE)
    assert process.stdout is not None and process.stderr is not None
    process.stdout.close()  # `| head -0`: the reader is gone before the command writes anything
    err = process.stderr.read().decode()
    assert process.wait(60) == EXIT_BROKEN_PIPE
    assert err == ""  # no traceback, no "Exception ignored" on exit


def test_the_same_commands_still_write_everything_to_a_reader_that_stays(store: tuple[Path, Path]) -> None:
    _, path = store
    process = _bsp(["sessions", "export", "--csv", "-", "--store", str(path)], stdout=subprocess.PIPE)
    out, err = process.communicate(timeout=60)
    assert process.returncode == 0, err
    header, *rows = out.decode().splitlines()
    assert header.startswith("subject,")
    per_subject = [sum(row.startswith(f"{s},") for row in rows) for s in ("S01", "S02", "S03")]
    assert per_subject[0] > 0 and per_subject == [per_subject[0]] * 3 and sum(per_subject) == len(rows)


@pytest.mark.parametrize("command", COMMANDS)
def test_ctrl_c_names_the_command_and_exits_130(
    command: str, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    def interrupted(args: argparse.Namespace) -> int:
        raise KeyboardInterrupt

    real = bsp_ros.cli.build_parser

    def parser_with_interrupt() -> argparse.ArgumentParser:
        parser = real()
        parser.set_defaults(_run=interrupted)
        for action in parser._subparsers._group_actions:  # type: ignore[union-attr]
            for sub in action.choices.values():  # type: ignore[union-attr]
                sub.set_defaults(_run=interrupted)
        return parser

    monkeypatch.setattr(bsp_ros.cli, "build_parser", parser_with_interrupt)
    argv = {"identify": ["identify", "x"], "tare": ["tare", "x", "--out", "y"], "plan": PLAN, "play": ["play", "x"]}
    argv |= {"report": ["report", "S01", "--out", "r"], "record": ["record", "/t", "--out", "d"]}
    argv |= {
        "simulate": ["simulate", "--out", "d"],
        "sessions": ["sessions", "list"],
        "subjects": ["subjects", "show", "S01"],
    }
    code = main(argv.get(command, [command]))
    assert code == EXIT_INTERRUPTED
    assert capsys.readouterr().err == f"bsp {command}: interrupted\n"


def test_a_real_sigint_during_a_command_is_reported_by_name() -> None:
    code = (
        "import signal, sys, bsp_ros.cli\n"
        # As at a terminal: a suite started in the background (`pytest &` in a script) hands its children SIGINT
        # ignored, and Python then installs no handler (the child ran on for minutes: a 60 s timeout).
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        # 'ready' from inside main's handler (build_parser is called there): a 'ready' printed before main left a
        # window in which the signal ended Python itself (-2, once in ~10 runs on a loaded machine).
        "build = bsp_ros.cli.build_parser\n"
        "def announced():\n"
        "    print('ready', flush=True)\n"
        "    return build()\n"
        "bsp_ros.cli.build_parser = announced\n"
        f"sys.exit(bsp_ros.cli.main({[*PLAN[:-1], '100000', '--duration', '600']!r}))\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    process = subprocess.Popen(
        [sys.executable, "-c", code], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert process.stdout is not None
    assert process.stdout.readline() == "ready\n"
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    assert process.returncode == EXIT_INTERRUPTED
    assert err == "bsp plan: interrupted\n"
    assert out == ""
