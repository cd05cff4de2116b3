"""How an estimate was made, as closed vocabularies: the identification method and the live node's mode.

Both are ``StrEnum``: a member is its string, so a JSON document, a ROS parameter and a stored session carry the
same words as before (``"joint"``, ``"windowed"``) and compare equal to them.
"""

from __future__ import annotations

from enum import StrEnum

__all__ = ["OFFLINE_METHODS", "LiveMode", "Method"]


class Method(StrEnum):
    """The identification method (an estimate's ``method``, ``bsp identify --method``)."""

    JOINT = "joint"  # every joint in one stacked bounded least squares, then the model checks
    PAPER = "paper"  # the method paper's sequential procedure, wrist to shoulder
    RECURSIVE = "recursive"  # the live per-sample filter (bsp_identifier's recursive mode)


#: The methods a recorded session can be identified with (`bsp identify --method`).
OFFLINE_METHODS: tuple[Method, ...] = (Method.JOINT, Method.PAPER)


class LiveMode(StrEnum):
    """How `bsp_identifier` estimates (its ``mode`` parameter, a live estimate's ``mode``)."""

    WINDOWED = "windowed"  # the newest window_s of samples identified as `bsp identify` would, each update
    RECURSIVE = "recursive"  # the per-sample filter, held to its window's checked estimate
