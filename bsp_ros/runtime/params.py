"""Node parameters as ROS 2 gives them: ros__parameters YAML files, ``name:=value`` overrides, typed and ranged."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from bsp_ros.errors import InputError, RuntimeBackendError

__all__ = [
    "ParamArgs",
    "check_parameter",
    "node_overrides",
    "parse_param_args",
    "rclpy_cli_args",
]


@dataclass(frozen=True)
class ParamArgs:
    """Parameter sources from the command line, in the order ROS applies them.

    Attributes
    ----------
    files : tuple of Path
        ``--params-file`` YAML files (``/**:`` / ``<node>:`` sections with ``ros__parameters``).
    overrides : dict
        ``--param name:=value`` (or ``-p``) values, parsed as YAML like ROS does; they win over files.
    """

    files: tuple[Path, ...] = ()
    overrides: dict[str, Any] = field(default_factory=dict)


def parse_param_args(args: Sequence[str]) -> tuple[ParamArgs, list[str]]:
    """Split ``--params-file FILE`` and ``--param name:=value`` / ``-p name:=value`` off a command line.

    ``--ros-args`` and ``--`` markers are dropped, so a ROS 2 style command line works as well.

    Parameters
    ----------
    args : sequence of str
        Command line arguments without the program name.

    Returns
    -------
    tuple of (ParamArgs, list of str)
        The parameter sources and the arguments left over.
    """
    files: list[Path] = []
    overrides: dict[str, Any] = {}
    rest: list[str] = []
    items = list(args)
    i = 0
    while i < len(items):
        arg = items[i]
        value: str | None = None
        key = arg
        if "=" in arg and arg.startswith("--params-file="):
            key, value = arg.split("=", 1)
        if key in ("--params-file", "--param", "-p"):
            if value is None:
                if i + 1 >= len(items):
                    raise InputError(f"{arg} needs a value")
                value = items[i + 1]
                i += 1
            if key == "--params-file":
                files.append(Path(value))
            else:
                name, sep, text = value.partition(":=")
                if not sep or not name:
                    raise InputError(f"{key} wants name:=value, got {value!r}")
                overrides[name] = yaml.safe_load(text) if text else ""
        elif arg not in ("--ros-args", "--"):
            rest.append(arg)
        i += 1
    return ParamArgs(tuple(files), overrides), rest


def rclpy_cli_args(param_args: ParamArgs) -> list[str]:
    """Return the ``--ros-args`` arguments that give rclpy the same parameters.

    Parameters
    ----------
    param_args : ParamArgs
        Parameter sources.

    Returns
    -------
    list of str
        ``["--ros-args", "--params-file", F, "-p", "name:=value", ...]`` (empty if no sources).
    """
    if not param_args.files and not param_args.overrides:
        return []
    out = ["--ros-args"]
    for path in param_args.files:
        out += ["--params-file", str(path)]
    for name, value in param_args.overrides.items():
        text = yaml.safe_dump(value, default_flow_style=True).strip()
        text = text.removesuffix("\n...").removesuffix("...").strip()
        out += ["-p", f"{name}:={text}"]
    return out


def _fqn_pattern(key: str) -> re.Pattern[str]:
    # rcl: a node key without a leading slash is relative to the root namespace; `*` matches one
    # name token and `**` any number of tokens.
    key = key if key.startswith("/") else "/" + key
    parts: list[str] = []
    for token in key.strip("/").split("/"):
        if token == "**":
            parts.append(r"(?:/[^/]+)*")
        elif token == "*":
            parts.append(r"/[^/]+")
        else:
            parts.append("/" + re.escape(token))
    return re.compile("".join(parts) + "$")


def _flatten(prefix: str, values: Mapping[str, Any], out: dict[str, Any]) -> None:
    for key, value in values.items():
        name = f"{prefix}.{key}" if prefix else str(key)
        if isinstance(value, Mapping):
            _flatten(name, value, out)
        else:
            out[name] = value


def node_overrides(param_args: ParamArgs, node_fqn: str) -> dict[str, Any]:
    """Return the parameter values the sources give a node, as ROS 2 resolves them.

    Wildcard sections (``/**:``) apply before sections naming the node; later files win over
    earlier ones, and ``--param`` overrides win over all files. Nested keys flatten with ``.``.

    Parameters
    ----------
    param_args : ParamArgs
        Parameter sources.
    node_fqn : str
        Fully qualified node name, e.g. ``"/wrench_filter"`` or ``"/cell1/wrench_filter"``.

    Returns
    -------
    dict
        Parameter name to value.
    """
    values: dict[str, Any] = {}
    for path in param_args.files:
        try:
            document = yaml.safe_load(path.read_text(encoding="utf-8"))
        except (OSError, yaml.YAMLError) as exc:
            raise InputError(f"cannot read parameter file {str(path)!r}: {exc}") from exc
        if document is None:
            continue
        if not isinstance(document, Mapping):
            raise InputError(f"parameter file {str(path)!r} must map node names to ros__parameters")
        wildcard: list[Mapping[str, Any]] = []
        exact: list[Mapping[str, Any]] = []
        for key, section in document.items():
            if not isinstance(section, Mapping) or "ros__parameters" not in section:
                raise InputError(f"parameter file {str(path)!r}: section {key!r} has no ros__parameters")
            if _fqn_pattern(str(key)).match(node_fqn):
                (wildcard if "*" in str(key) else exact).append(section["ros__parameters"] or {})
        for params in wildcard + exact:
            _flatten("", params, values)
    values.update(param_args.overrides)
    return values


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "integer"
    if isinstance(value, float):
        return "double"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list | tuple):
        kinds = {_kind(item) for item in value}
        if len(kinds) == 1:
            return f"{kinds.pop()}_array"
        if not kinds:
            return "empty_array"
    raise InputError(f"unsupported parameter value {value!r} of type {type(value).__name__}")


def check_parameter(
    node: str, name: str, value: Any, default: Any, lo: float | None = None, hi: float | None = None
) -> Any:
    """Return ``value`` if it has the type of ``default`` and lies in ``[lo, hi]``; raise otherwise.

    Like ROS 2 parameters, the type is fixed by the default: an integer (YAML ``1``) is rejected for a
    floating point parameter (write ``1.0``). Floating point values must be finite.

    Parameters
    ----------
    node : str
        Node name, for the message.
    name : str
        Parameter name.
    value : object
        The value to check.
    default : object
        The declared default, fixing the type.
    lo, hi : float, optional
        Inclusive range for numeric parameters.

    Returns
    -------
    object
        ``value`` (tuples become lists).

    Raises
    ------
    InputError
        Naming the node, the parameter and the offending value.
    """
    want, got = _kind(default), _kind(value)
    if got != want and not (got == "empty_array" and want.endswith("_array")) and want != "empty_array":
        hint = " (write it with a decimal point, e.g. 1.0)" if (want, got) == ("double", "integer") else ""
        raise InputError(f"parameter {name!r} of node {node!r} must be {want}, got {got} {value!r}{hint}")
    if lo is not None or hi is not None:
        if want not in ("integer", "double"):
            raise RuntimeBackendError(f"parameter {name!r}: a range needs a numeric default, got {default!r}")
        low = -math.inf if lo is None else lo
        high = math.inf if hi is None else hi
        if not (low <= value <= high):
            raise InputError(f"parameter {name!r} of node {node!r} must be within [{low:g}, {high:g}], got {value!r}")
    if want == "double" and not math.isfinite(value):
        raise InputError(f"parameter {name!r} of node {node!r} must be finite, got {value!r}")
    return list(value) if isinstance(value, tuple) else value
