"""argparse `type=` converters for the subcommands; light at import (numpy only when an option is given)."""

from __future__ import annotations

import argparse
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
            raise argparse.ArgumentTypeError(f"must be a finite number within [{lo:g}, {hi:g}], got {text!r}") from None

    convert.__name__ = f"float within [{lo:g}, {hi:g}]"
    return convert
