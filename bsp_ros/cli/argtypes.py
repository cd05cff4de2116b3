"""argparse `type=` converters for the subcommands; light at import (numpy only when an option is given)."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

from bsp_ros.errors import InputError


def positive_float(text: str) -> float:
    """``text`` as a float if it is finite and > 0, else an argparse error naming the value."""
    from bsp_ros.validation import check_positive

    try:
        return check_positive("value", text)
    except InputError:
        raise argparse.ArgumentTypeError(f"must be a finite number greater than 0, got {text!r}") from None


def float_within(lo: float, hi: float) -> Callable[[str], float]:
    """A converter accepting a finite float in ``[lo, hi]``, else an argparse error naming the value."""

    def convert(text: str) -> float:
        from bsp_ros.validation import check_finite_scalar

        try:
            return check_finite_scalar("value", text, lo, hi)
        except InputError:
            raise argparse.ArgumentTypeError(f"must be a finite number{_bounds(lo, hi)}, got {text!r}") from None

    convert.__name__ = f"float{_bounds(lo, hi)}"
    return convert


def _bounds(lo: float, hi: float) -> str:
    if math.isinf(lo) and math.isinf(hi):
        return ""
    if math.isinf(hi):
        return f" >= {lo:g}"
    if math.isinf(lo):
        return f" <= {hi:g}"
    return f" within [{lo:g}, {hi:g}]"


def finite_float(text: str) -> float:
    """``text`` as a finite float, else an argparse error naming the value."""
    return float_within(-math.inf, math.inf)(text)


def nonnegative_float(text: str) -> float:
    """``text`` as a finite float >= 0, else an argparse error naming the value."""
    return float_within(0.0, math.inf)(text)


def int_within(lo: int, hi: int) -> Callable[[str], int]:
    """A converter accepting an integer in ``[lo, hi]``, else an argparse error naming the value."""

    def convert(text: str) -> int:
        try:
            number = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be an integer within [{lo}, {hi}], got {text!r}") from None
        if not lo <= number <= hi:
            raise argparse.ArgumentTypeError(f"must be an integer within [{lo}, {hi}], got {text!r}")
        return number

    convert.__name__ = f"integer within [{lo}, {hi}]"
    return convert


def positive_at_most(hi: float) -> Callable[[str], float]:
    """A converter accepting a finite float in ``(0, hi]``, else an argparse error naming the value."""

    def convert(text: str) -> float:
        number = positive_float(text)
        if number > hi:
            raise argparse.ArgumentTypeError(f"must be a finite number within (0, {hi:g}], got {text!r}")
        return number

    convert.__name__ = f"float within (0, {hi:g}]"
    return convert
