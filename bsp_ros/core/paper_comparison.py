"""The method paper's mechanical arm (Table 1): its method and ours side by side on the same data."""

from __future__ import annotations

from dataclasses import dataclass

from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.joint import identify_joint
from bsp_ros.core.identification.paper import identify_paper
from bsp_ros.core.simulation import SimulatedSession, paper_mechanical_arm_cell, simulate_cell

# The paper's own errors on the real mechanical arm (Table 1, upper part), in percent.
PAPER_REPORTED_ERROR_PCT = {
    ("static_moment_kgm", "forearm"): 3.8,
    ("static_moment_kgm", "upper_arm"): 1.8,
    ("coulomb_nm", "elbow"): 7.7,
    ("coulomb_nm", "shoulder"): 10.6,
}
LABELS = {
    ("static_moment_kgm", "forearm"): "m2 l2 (kgm)",
    ("static_moment_kgm", "upper_arm"): "m1 l1 + a1 m2 (kgm)",
    ("coulomb_nm", "elbow"): "tau_p2 Coulomb (Nm)",
    ("coulomb_nm", "shoulder"): "tau_p1 Coulomb (Nm)",
}


@dataclass(frozen=True, kw_only=True)
class ComparisonRow:
    """One identifiable parameter: truth, both estimates and their relative errors (%)."""

    label: str
    truth: float
    paper: float
    ours: float
    ours_std: float
    paper_error_pct: float
    ours_error_pct: float
    paper_reported_error_pct: float


def compare_on_mechanical_arm(seed: int = 0, duration_s: float = 120.0) -> tuple[list[ComparisonRow], SimulatedSession]:
    """Simulate the Table 1 arm with paper-like noise and identify it with both methods.

    Returns
    -------
    rows : one per identifiable parameter.
    session : the simulated session (for its truth).
    """
    session = simulate_cell(paper_mechanical_arm_cell(seed=seed, duration_s=duration_s))
    data = identification_data_from_session(session.session)
    ours, paper = identify_joint(data), identify_paper(data)
    truth = session.truth.to_dict()
    rows = []
    for (key, owner), label in LABELS.items():
        true = float(truth["segments" if key == "static_moment_kgm" else "joints"][owner][key])
        paper_value, ours_value = paper.value(key, owner), ours.value(key, owner)
        rows.append(
            ComparisonRow(
                label=label,
                truth=true,
                paper=paper_value,
                ours=ours_value,
                ours_std=ours.std_of(key, owner),
                paper_error_pct=100 * abs(paper_value - true) / true,
                ours_error_pct=100 * abs(ours_value - true) / true,
                paper_reported_error_pct=PAPER_REPORTED_ERROR_PCT[(key, owner)],
            )
        )
    return rows, session


def format_table(rows: list[ComparisonRow]) -> str:
    """A plain-text table of :func:`compare_on_mechanical_arm` rows."""
    lines = [
        f"{'parameter':24s} {'truth':>8s} {'paper method':>13s} {'err%':>6s} {'ours':>8s} {'+- std':>8s} "
        f"{'err%':>6s} {'paper Table 1 err%':>19s}"
    ]
    for r in rows:
        lines.append(
            f"{r.label:24s} {r.truth:8.4f} {r.paper:13.4f} {r.paper_error_pct:6.2f} {r.ours:8.4f} {r.ours_std:8.5f} "
            f"{r.ours_error_pct:6.2f} {r.paper_reported_error_pct:19.1f}"
        )
    return "\n".join(lines)
