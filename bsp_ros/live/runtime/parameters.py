"""A node's ROS parameters as a table: declared with ranged descriptors, and printed by ``--help``."""

from __future__ import annotations

import inspect
import math
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from bsp_ros.errors import InputError

__all__ = ["Param", "declare_parameters", "help_text", "wants_help"]

_INT64_MIN, _INT64_MAX = -(2**63), 2**63 - 1


@dataclass(frozen=True, kw_only=True)
class Param:
    """One ROS parameter of a node: its default fixes the type (a float parameter wants ``1.0``, not ``1``).

    Attributes
    ----------
    name, default, description : as declared; a default of None leaves the parameter unset (declared with the type
        ``kind``: its value is None unless given).
    unit : shown after the description, e.g. ``"Hz"``.
    lo, hi : inclusive range of a numeric parameter (a ``FloatingPointRange`` / ``IntegerRange``).
    choices : the allowed values of a string parameter.
    kind : the type of a parameter without a default (``float``, ``int``, ``str`` or ``bool``).
    """

    name: str
    default: Any
    description: str
    unit: str = ""
    lo: float | None = None
    hi: float | None = None
    choices: tuple[str, ...] = ()
    kind: type | None = None

    @property
    def value_type(self) -> type:
        """The parameter's type: its default's, or ``kind`` for one without a default."""
        if self.default is not None:
            return type(self.default)
        if self.kind is None:
            raise TypeError(f"parameter {self.name!r}: one without a default needs its kind")
        return self.kind

    def text(self) -> str:
        """Description with unit, range and choices, as in the descriptor and ``--help``."""
        out = self.description + (f" [{self.unit}]" if self.unit else "")
        if self.lo is not None or self.hi is not None:
            low = "-inf" if self.lo is None else f"{self.lo:g}"
            high = "inf" if self.hi is None else f"{self.hi:g}"
            out += f" (range {low} .. {high})"
        if self.choices:
            out += f" (one of {', '.join(self.choices)})"
        return out


def _descriptor(param: Param) -> Any:
    from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

    # read_only: the nodes read their parameters once at start; a later `ros2 param set` is refused, not ignored.
    descriptor = ParameterDescriptor(description=param.text(), read_only=True)
    if param.lo is not None or param.hi is not None:
        if param.value_type not in (int, float):
            raise TypeError(f"parameter {param.name!r}: a range needs a numeric default")
        if param.value_type is int:
            low = _INT64_MIN if param.lo is None else math.ceil(param.lo)
            high = _INT64_MAX if param.hi is None else math.floor(param.hi)
            descriptor.integer_range = [IntegerRange(from_value=low, to_value=high, step=0)]
        else:
            low_f = -sys.float_info.max if param.lo is None else float(param.lo)
            high_f = sys.float_info.max if param.hi is None else float(param.hi)
            descriptor.floating_point_range = [FloatingPointRange(from_value=low_f, to_value=high_f, step=0.0)]
    return descriptor


def declare_parameters(node: Any, params: Sequence[Param]) -> dict[str, Any]:
    """Declare ``params`` on an ``rclpy.node.Node`` and return their values (overrides applied).

    rclpy checks types and ranges against the descriptors; this adds finiteness and ``choices``.

    Raises
    ------
    InputError
        Naming the node, the parameter and the offending value.
    """
    from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
    from rclpy.parameter import Parameter

    unset = {float: Parameter.Type.DOUBLE, int: Parameter.Type.INTEGER, str: Parameter.Type.STRING}
    values: dict[str, Any] = {}
    where = f"node {node.get_name()!r}"
    for param in params:
        # A parameter without a default is declared by its type: unset (None) unless given.
        default = param.default if param.default is not None else unset.get(param.value_type, Parameter.Type.BOOL)
        try:
            value = node.declare_parameter(param.name, default, _descriptor(param)).value
        except InvalidParameterTypeException as exc:
            hint = " (write it with a decimal point, e.g. 1.0)" if param.value_type is float else ""
            raise InputError(f"parameter {param.name!r} of {where}: {exc}{hint}") from exc
        except InvalidParameterValueException as exc:
            raise InputError(f"parameter {param.name!r} of {where}: {exc}") from exc
        if isinstance(value, float) and not math.isfinite(value):
            raise InputError(f"parameter {param.name!r} of {where} must be finite, got {value!r}")
        if param.choices and value not in param.choices:
            raise InputError(f"parameter {param.name!r} of {where} must be one of {param.choices}, got {value!r}")
        values[param.name] = list(value) if isinstance(value, tuple) else value
    return values


def wants_help(args: Sequence[str] | None) -> bool:
    """True if ``--help``/``-h`` comes before any ``--ros-args`` in a command line (``sys.argv`` when None)."""
    items = list(sys.argv if args is None else args)
    head = items[: items.index("--ros-args")] if "--ros-args" in items else items
    return "--help" in head or "-h" in head


def help_text(name: str, summary: str, params: Sequence[Param]) -> str:
    """The ``--help`` of a node executable: usage and every parameter with its type, default and meaning."""
    lines = [
        f"usage: {name} [--help] [--ros-args [-p NAME:=VALUE ...] [--params-file FILE] ...]",
        "",
        inspect.cleandoc(summary),
        "",
        "parameters (set with `--ros-args -p name:=value` or a `--params-file` YAML; floats need a decimal point):",
    ]
    width = max(len(p.name) for p in params) if params else 0
    for p in params:
        kind = p.value_type.__name__
        lines.append(f"  {p.name:<{width}}  {kind:<5} default {p.default!r:<20} {p.text()}")
    return "\n".join(lines)
