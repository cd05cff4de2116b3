"""The parameters `bsp_cell.launch.py` gives each node, as a plain function of its launch arguments (the launch
package is not needed to test them)."""

from __future__ import annotations

from typing import Any

__all__ = ["node_parameters"]


def node_parameters(params_file: str, cell_file: str = "") -> list[Any]:
    """The ``parameters`` of a node the launch file starts: the params file, then ``cell_file`` where it is given.

    Later entries win, so a ``cell_file`` argument given at launch overrides the params file's; one left empty is not
    passed at all, and the params file's ``cell_file`` (else the shipped cell) stands.

    Parameters
    ----------
    params_file : the ros__parameters YAML (launch argument ``params_file``).
    cell_file : the cell description (launch argument ``cell_file``; '' or blank: not given).

    Returns
    -------
    list
        ``[params_file]`` or ``[params_file, {"cell_file": cell_file}]``.
    """
    given = cell_file.strip()
    return [params_file, {"cell_file": given}] if given else [params_file]
