"""Inputs shared by the planning tests: the limits, the shoulder, the passive truth, the prior arm."""

from __future__ import annotations

from bsp_ros.core import simulation as sim
from bsp_ros.core.planning import NominalArm

SHOULDER_YZ_M = (0.0, 1.2)
RANGES_DEG = ((-70.0, -10.0), (10.0, 100.0), (-20.0, 20.0))
# The passive truth: elastic offsets 0.2 Nm at every joint, elbow stiffness 1.5 Nm/rad (neutral 0, so
# the identified offset is the truth's offset), Coulomb as the default human cell.
ELASTIC_TRUTH = sim.PassiveTruth(
    coulomb_nm=(0.5, 0.28, 0.06), offset_nm=(0.2, 0.2, 0.2), stiffness_nm_per_rad=(0.0, 1.5, 0.0)
)


def nominal_arm() -> NominalArm:
    """The anthropometric arm for the simulator's default subject's lengths (the planner's prior)."""
    return NominalArm.from_anthropometry(sim.human_arm_cell().subject.lengths_m)
