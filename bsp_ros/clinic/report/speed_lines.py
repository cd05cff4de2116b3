"""The therapist's line per joint that resisted a fast stretch more than a slow one (a session at two speeds)."""

from __future__ import annotations

from bsp_ros.clinic.report.analysis import Analysis
from bsp_ros.clinic.report.labels import PART_NAMES
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.joint.speed_split import DIRECTIONS, MIN_SPASTIC_NM, DirectionPart

__all__ = ["speed_dependence_line", "speed_dependence_lines"]


def speed_dependence_line(finding: Finding) -> str | None:
    """``"Elbow: resistance to a fast stretch 0.8 +- 0.1 Nm more than to a slow one (possible spasticity)"`` from a
    ``speed_dependent_resistance`` note whose part exceeds 3 std; None for any other finding. A part in one direction
    of motion only is what a stretch reflex gives (possible spasticity); in both, a speed-dependent resistance."""
    if finding.code is not FindingCode.SPEED_DEPENDENT_RESISTANCE or not finding.values.get("exceeds"):
        return None
    v = finding.values
    part, std = float(v["part_nm"]), float(v["std_nm"])
    more = "more" if part > 0 else "less"
    both = all(
        DirectionPart(part_nm=float(v[f"{d}_nm"]), std_nm=float(v[f"{d}_std_nm"])).exceeds
        and abs(float(v[f"{d}_nm"])) >= MIN_SPASTIC_NM
        for d in DIRECTIONS
    )
    cause = "speed-dependent in both directions of motion" if both else "possible spasticity"
    joint = PART_NAMES.get(finding.where, finding.where)
    return f"{joint}: resistance to a fast stretch {abs(part):.2g} +- {std:.1g} Nm {more} than to a slow one ({cause})"


def speed_dependence_lines(analysis: Analysis) -> list[tuple[str, str]]:
    """``(session, line)`` for each usable session and joint with a speed-dependent part, in session order."""
    out = []
    for record in analysis.sessions:
        if not record.quality.valid:
            continue
        for finding in record.quality.findings:
            line = speed_dependence_line(finding)
            if line is not None:
                out.append((f"Session {analysis.label_of(record)}", line))
    return out
