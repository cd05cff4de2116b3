"""`bsp` starts light: building its parser imports no numerics, plotting or middleware, and lists every subcommand."""

from __future__ import annotations

import importlib
import pkgutil
import subprocess
import sys

import bsp_ros.cli
from bsp_ros.cli import COMMANDS, identify

HEAVY = ("numpy", "scipy", "matplotlib", "rclpy", "rosbags", "mcap", "yaml")


def test_building_the_parser_imports_no_heavy_module() -> None:
    code = (
        "import sys, bsp_ros.cli\n"
        "bsp_ros.cli.build_parser()\n"
        f"print(sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY!r})))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]", done.stdout


def test_version_runs_as_a_module_without_heavy_imports() -> None:
    code = (
        "import runpy, sys\n"
        "sys.argv = ['bsp', '--version']\n"
        "try:\n"
        "    runpy.run_module('bsp_ros.cli', run_name='__main__')\n"
        "except SystemExit as stop:\n"
        f"    print(stop.code, sorted({{m.split('.')[0] for m in sys.modules}} & set({HEAVY!r})))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.startswith(f"bsp_ros {bsp_ros.__version__}\n")
    assert done.stdout.splitlines()[-1] == "0 []"


def test_identifying_a_bag_does_not_import_the_bag_writer() -> None:
    """`bsp identify` reads: the writer's modules (mcap's writer among them) are not its cost."""
    code = (
        "import sys\n"
        "from bsp_ros.bag.offline import identify_bag\n"
        "from bsp_ros.bag import read_session, BagCorruptError\n"
        "print(sorted(m for m in sys.modules if m in ('bsp_ros.bag.writer', 'mcap.writer')))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]", done.stdout


def test_the_command_table_lists_every_subcommand_module() -> None:
    names = [info.name for info in pkgutil.iter_modules(bsp_ros.cli.__path__) if not info.name.startswith("_")]
    modules = [importlib.import_module(f"bsp_ros.cli.{name}") for name in names]
    subcommands = {m.__name__.rsplit(".", 1)[1] for m in modules if hasattr(m, "add_parser") and hasattr(m, "run")}
    assert set(COMMANDS) == subcommands


def test_identify_offers_the_methods_the_pipeline_knows() -> None:
    from bsp_ros.core.pipeline import METHODS

    assert identify.METHODS == METHODS
