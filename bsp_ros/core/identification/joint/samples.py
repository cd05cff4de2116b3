"""The samples a stacked fit uses: rows with a trustworthy direction of motion, spikes left out, the problem."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.core.findings import Finding, FindingCode, note
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.joint.excitation import excitation_problems, motion_rows
from bsp_ros.core.identification.joint.extras import base_extras
from bsp_ros.core.identification.joint.outliers import wrench_spikes
from bsp_ros.core.identification.stacked import Extras, Problem, build_problem


@dataclass(frozen=True)
class Samples:
    """What :func:`usable_samples` found.

    Attributes
    ----------
    rows : (N, n) the rows used per joint; spikes : (N,) wrench spikes (left out of every joint's rows).
    extras : the dynamics blocks (None for a static model); problem : the stacked problem on ``rows``.
    problems : why the motion cannot support an estimate (excitation); warnings : the samples' notes.
    too_few : why there are too few usable samples to fit at all, or None.
    """

    rows: np.ndarray
    spikes: np.ndarray
    extras: Extras | None
    problem: Problem
    problems: list[Finding]
    warnings: list[Finding]
    too_few: Finding | None

    @property
    def usable(self) -> int:
        """Samples that are no wrench spike."""
        return int((~self.spikes).sum())


def usable_samples(data: IdentificationData, config: JointConfig, widths: np.ndarray | None = None) -> Samples:
    """The rows of ``data`` the stacked fit of ``config``'s passive model uses and its problem (with friction
    transition ``widths``, rad/s, where given), what the motion leaves unsupported, and the samples' notes."""
    rows, notes = motion_rows(data, config)
    spikes, spike_notes = wrench_spikes(data, config)
    rows &= ~spikes[:, None]
    extras = base_extras(data, config)
    problem = build_problem(data, config.passive, rows, widths, extras)
    p = len(problem.names)
    fewest = int(rows.sum(axis=0).min())
    too_few = data.t_ns.size < max(config.min_samples, 2 * p) or fewest < p
    return Samples(
        rows,
        spikes,
        extras,
        problem,
        excitation_problems(data, rows, config),
        [note(FindingCode.DATA_NOTE, w) for w in data.warnings] + spike_notes + notes,
        Finding(code=FindingCode.TOO_FEW_USABLE_SAMPLES, values={"fewest": fewest}) if too_few else None,
    )
