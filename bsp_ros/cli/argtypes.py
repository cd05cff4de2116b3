"""argparse `type=` converters for the subcommands; light at import (numpy only when an option is given)."""

from __future__ import annotations

import argparse

from bsp_ros.errors import InputError


def positive_float(text: str) -> float:
    """``text`` as a float if it is finite and > 0, else an argparse error naming the value."""
    from bsp_ros.validation import check_positive

    try:
        return check_positive("value", text)
    except InputError:
        raise argparse.ArgumentTypeError(f"must be a finite number greater than 0, got {text!r}") from None
