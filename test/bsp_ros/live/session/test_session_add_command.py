"""The `bsp sessions add` command a recorder logs for a kept recording stores it as the recorder would have."""

from __future__ import annotations

import shlex
from pathlib import Path

from bsp_ros.bag import TopicMap
from bsp_ros.cli import build_parser
from bsp_ros.live.session.storing import IdentifySettings, add_command, add_options_for


def test_the_logged_add_command_carries_the_sessions_own_settings_and_cell(tmp_path: Path) -> None:
    topics = TopicMap(wrench="/cell 2/wrench")
    cell_file = tmp_path / "my cell.yaml"
    settings = IdentifySettings(
        passive="coulomb+offset+stiffness",
        tare_file=str(tmp_path / "t.yaml"),
        wrench_delay_s=0.004,
        marker_placement_sd_mm=3.0,
        topics=topics,
        cell_file=str(cell_file),
    )
    bag = tmp_path / "session 7"
    command = add_command(bag, "P007", True, add_options_for(settings, "north"))
    words = shlex.split(command)
    assert words[:3] == ["bsp", "sessions", "add"]
    args = build_parser().parse_args(words[1:])
    assert [Path(p) for p in args.input] == [bag]
    assert args.subject == "P007" and args.retest
    assert args.cell == "north"  # the store's cell name
    assert Path(args.cell_file) == cell_file  # the cell description, --cell-file for sessions add
    assert args.passive == "coulomb+offset+stiffness"
    assert args.wrench_topic == "/cell 2/wrench"
    assert Path(args.tare) == tmp_path / "t.yaml"
    assert args.wrench_delay_s == 0.004 and args.marker_placement_sd_mm == 3.0


def test_without_settings_the_command_is_the_bare_one(tmp_path: Path) -> None:
    assert add_command(tmp_path / "b", "P001", False) == f"bsp sessions add {tmp_path / 'b'} --subject P001"


def test_the_method_is_typed_from_the_recorder_to_the_options(tmp_path: Path) -> None:
    from bsp_ros.cli.identify_options import options_from_args
    from bsp_ros.core.methods import Method

    settings = IdentifySettings(method=Method.PAPER)
    command = add_command(tmp_path / "b", "P001", False, settings.add_options())
    args = build_parser().parse_args(shlex.split(command)[1:])
    options = options_from_args(args)
    assert options.method is Method.PAPER
    assert options_from_args(build_parser().parse_args(["identify", "b"])).method is Method.JOINT
