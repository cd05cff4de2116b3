"""bsp_cell.launch.py's ``cell_file`` and ``subject`` arguments: given, a node takes each after the params file (so it
wins); left empty, it is not passed and the params file's stands. The launch file runs here against stand-ins of the
launch packages, which have no wheels (ros2 launch runs it on a Jazzy cell)."""

from __future__ import annotations

import importlib.util
import sys
import types
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from bsp_ros.live.runtime.launch_parameters import node_parameters

LAUNCH_FILE = Path(__file__).resolve().parents[4] / "launch" / "bsp_cell.launch.py"
NODES = ("cell_simulator", "joint_angle_estimator", "bsp_identifier", "session_recorder", "arm_visualizer")


def test_a_cell_file_is_passed_only_where_given() -> None:
    assert node_parameters("p.yaml") == ["p.yaml"]
    assert node_parameters("p.yaml", "  ") == ["p.yaml"]
    assert node_parameters("p.yaml", "/cells/a.yaml") == ["p.yaml", {"cell_file": "/cells/a.yaml"}]


@dataclass
class _Entity:
    """A launch action as the launch file built it: its arguments."""

    args: tuple[Any, ...]
    kwargs: dict[str, Any] = field(default_factory=dict)


class _Declare(_Entity):
    pass


class _Opaque(_Entity):
    pass


class _Node(_Entity):
    pass


class _Configuration:
    def __init__(self, name: str) -> None:
        self.name = name

    def perform(self, context: Any) -> str:
        return str(context.launch_configurations[self.name])


def _module(name: str, **attributes: Any) -> types.ModuleType:
    module = types.ModuleType(name)
    module.__dict__.update(attributes)
    return module


@pytest.fixture
def launch_file(monkeypatch: pytest.MonkeyPatch) -> types.ModuleType:
    """The launch file imported against stand-ins of ament_index_python, launch and launch_ros."""

    def entity(kind: type[_Entity]) -> Any:
        return lambda *args, **kwargs: kind(args, kwargs)

    stand_ins = {
        "ament_index_python": _module("ament_index_python"),
        "ament_index_python.packages": _module(
            "ament_index_python.packages", get_package_share_directory=lambda package: f"/opt/share/{package}"
        ),
        "launch": _module("launch", LaunchContext=object, LaunchDescription=lambda entities: list(entities)),
        "launch.actions": _module(
            "launch.actions", DeclareLaunchArgument=entity(_Declare), OpaqueFunction=entity(_Opaque)
        ),
        "launch.conditions": _module("launch.conditions", IfCondition=lambda value: ("if", value.name)),
        "launch.substitutions": _module("launch.substitutions", LaunchConfiguration=_Configuration),
        "launch_ros": _module("launch_ros"),
        "launch_ros.actions": _module("launch_ros.actions", Node=entity(_Node)),
        "launch_ros.parameter_descriptions": _module(
            "launch_ros.parameter_descriptions", ParameterValue=lambda value, value_type: (value.name, value_type)
        ),
    }
    for name, module in stand_ins.items():
        monkeypatch.setitem(sys.modules, name, module)
    spec = importlib.util.spec_from_file_location("bsp_cell_launch", LAUNCH_FILE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _launch(launch_file: types.ModuleType, **given: str) -> dict[str, list[Any]]:
    """Executable -> its ``parameters``, for the launch arguments ``given`` (the others at their defaults)."""
    entities = launch_file.generate_launch_description()
    declared = {e.args[0]: e.kwargs["default_value"] for e in entities if isinstance(e, _Declare)}
    assert set(given) <= set(declared)
    context = types.SimpleNamespace(launch_configurations={**declared, **given})
    (opaque,) = [e for e in entities if isinstance(e, _Opaque)]
    nodes = opaque.kwargs["function"](context)
    return {node.kwargs["executable"]: node.kwargs["parameters"] for node in nodes}


def test_left_empty_the_cell_file_argument_leaves_the_params_files(launch_file: types.ModuleType) -> None:
    parameters = _launch(launch_file)
    assert set(parameters) == set(NODES)
    for executable, given in parameters.items():
        assert given[0] == "/opt/share/bsp_ros/config/bsp_cell.yaml", executable
        assert not any(isinstance(p, dict) and "cell_file" in p for p in given), executable
    # No subject argument: none passed, so a subject in the params file is not blanked.
    assert not any(isinstance(p, dict) and "subject" in p for p in parameters["session_recorder"])


def test_a_cell_file_argument_follows_the_params_file_so_it_wins(launch_file: types.ModuleType) -> None:
    parameters = _launch(launch_file, params_file="/cell/my_params.yaml", cell_file="/cell/my_cell.yaml")
    for executable, given in parameters.items():
        assert given[:2] == ["/cell/my_params.yaml", {"cell_file": "/cell/my_cell.yaml"}], executable


def test_a_subject_argument_follows_the_params_file_as_a_string_and_only_where_given(
    launch_file: types.ModuleType,
) -> None:
    parameters = _launch(launch_file, params_file="/cell/my_params.yaml", subject="007")
    assert parameters["session_recorder"] == ["/cell/my_params.yaml", {"subject": ("subject", str)}]
    for executable, given in parameters.items():  # the other nodes have no subject
        if executable != "session_recorder":
            assert given == ["/cell/my_params.yaml"], executable
    blank = _launch(launch_file, params_file="/cell/my_params.yaml", subject="  ")
    assert blank["session_recorder"] == ["/cell/my_params.yaml"]
