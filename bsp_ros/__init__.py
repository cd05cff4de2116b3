"""bsp_ros: body segment parameters and passive joint moments of the arm, identified online.

The Python API (docs/api.md): :func:`identify`, :func:`simulate`, :func:`open_store`, :func:`to_records` and
:func:`to_frame`, loaded on first use so that ``import bsp_ros`` stays light.
"""

from __future__ import annotations

from typing import Any

__version__ = "0.1.0"

__all__ = ["__version__", "identify", "open_store", "simulate", "to_frame", "to_records"]

_API = {"identify", "open_store", "simulate", "to_frame", "to_records"}


def __getattr__(name: str) -> Any:
    """The API's functions, imported when first asked for (PEP 562)."""
    if name in _API:
        from bsp_ros import api

        return getattr(api, name)
    raise AttributeError(f"module 'bsp_ros' has no attribute {name!r}")
