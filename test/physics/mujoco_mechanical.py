"""The method paper's 2-segment mechanical arm as a MuJoCo cell (``mujoco_cell``): its parameters and protocol.

Test support (not part of the installed package). Kodek and Munih (2006) verified their method on a CAD-designed
2-DOF arm: aluminium segments with brass weights attached "to obtain masses comparable to the human arm", rubber
brakes at each joint for a Coulomb friction measured with load cells, coupled to the robot "by using a screw attached
to a bearing" (``mujoco_cell`` couples a 2-segment chain through a ``connect``: no moment at the handle). Table 1
gives m1 l1 = 0.260 kg m, m2 = 1.160 kg, m2 l2 = 0.130 kg m and the brakes' 0.139 Nm (shoulder) and 0.161 Nm
(elbow); lengths and m1 are not given, and are taken as ``SubjectTruth.paper_mechanical_arm()`` takes them
(a1 = a2 = 0.30 m, m1 = 1.5 kg).

Inertias (the paper gives none): each segment is an aluminium bar (``BAR_*``: 0.30 m long, 30 mm in the arm's
plane, 10 mm across, 2700 kg/m^3: 0.243 kg, its centre at mid-length) carrying one brass block (``LOAD_*``: 40 mm
along the segment, 40 mm deep in the plane) of the rest of the segment's mass, placed so that the segment's COM
is the table's. Both are rectangular cuboids, I = m (a^2 + h^2) / 12 about their centre, moved to the segment's COM
by the parallel-axis theorem. The blocks sit near the COMs (0.178 m and 0.102 m from the joints), so the nominal
arm's I_com are 0.0023 kg m^2 (upper arm) and 0.0025 kg m^2 (forearm), a quarter of the uniform slender bars'
m a^2 / 12 that ``SubjectTruth.paper_mechanical_arm()`` assumes (0.0113, 0.0087).
"""

from __future__ import annotations

import numpy as np
from mujoco_cell import ArmParams

from bsp_ros.core.simulation import SubjectTruth, TrajectorySpec, paper_mechanical_arm_cell

ALUMINIUM_KG_M3 = 2700.0
BAR_DEPTH_M = 0.030  # in the arm's plane (normal to the segment axis)
BAR_WIDTH_M = 0.010  # across the plane (along x): no part in the inertia about x
LOAD_LENGTH_M = 0.040  # the brass block along the segment
LOAD_DEPTH_M = 0.040  # the brass block in the plane, normal to the axis
PAPER_ARM_COULOMB_NM = (0.139, 0.161)  # Table 1's x_ref of the brakes (shoulder, elbow)
# A seeded arm: a manufacturing spread, masses and COM distances times 1 + N(0, 2 %), each brake's friction
# times U(0.7, 1.3) (screw-adjusted by hand).
MASS_SD = 0.02
COM_SD = 0.02
FRICTION_RANGE = (0.7, 1.3)


def segment_inertia_kgm2(mass_kg: float, com_m: float, length_m: float) -> float:
    """The moment of inertia about the COM (rotation about x) of an aluminium bar carrying one brass block, kg m^2.

    Parameters
    ----------
    mass_kg : the segment's mass, kg (more than the bar's).
    com_m : its COM distance from the proximal joint, m; the block sits where it brings the COM there.
    length_m : the bar's length, m (its centre at ``length_m / 2``).

    Returns
    -------
    float
        ``I_com``, kg m^2.

    Raises
    ------
    ValueError
        If the mass is not more than the bar's, or the block would have to sit off the bar.
    """
    bar_kg = ALUMINIUM_KG_M3 * length_m * BAR_DEPTH_M * BAR_WIDTH_M
    load_kg = mass_kg - bar_kg
    if load_kg <= 0.0:
        raise ValueError(f"mass_kg = {mass_kg!r} is not more than the bar's {bar_kg:.3f} kg")
    load_at_m = (mass_kg * com_m - bar_kg * length_m / 2.0) / load_kg
    if not 0.0 <= load_at_m <= length_m:
        raise ValueError(f"com_m = {com_m!r} puts the block at {load_at_m:.3f} m, off the {length_m!r} m bar")
    bar = bar_kg * ((length_m**2 + BAR_DEPTH_M**2) / 12.0 + (length_m / 2.0 - com_m) ** 2)
    load = load_kg * ((LOAD_LENGTH_M**2 + LOAD_DEPTH_M**2) / 12.0 + (load_at_m - com_m) ** 2)
    return float(bar + load)


def mechanical_arm(seed: int | None = None) -> ArmParams:
    """The paper's mechanical arm: Table 1 (``seed`` None) or a seeded arm of the same drawing.

    A seed draws masses and COM distances times ``1 + N(0, MASS_SD)`` and ``1 + N(0, COM_SD)`` and each brake's
    friction times U(``FRICTION_RANGE``); inertias follow from the bar and block (:func:`segment_inertia_kgm2`).
    No springs, no damping, COMs on the axis.

    Parameters
    ----------
    seed : None for the nominal arm, else the seed of the spread (``np.random.default_rng([seed, 2006])``).

    Returns
    -------
    ArmParams
        A 2-segment arm (upper arm, forearm): ``record`` / ``write_bag`` make a bag with markers shoulder, elbow,
        hand, as ``bsp simulate --subject paper-arm`` does.
    """
    nominal = SubjectTruth.paper_mechanical_arm()
    masses, coms = np.asarray(nominal.masses_kg), np.asarray(nominal.com_m)
    friction = np.asarray(PAPER_ARM_COULOMB_NM)
    if seed is not None:
        rng = np.random.default_rng([seed, 2006])
        masses = masses * (1.0 + rng.normal(0.0, MASS_SD, 2))
        coms = coms * (1.0 + rng.normal(0.0, COM_SD, 2))
        friction = friction * rng.uniform(*FRICTION_RANGE, 2)
    lengths = tuple(float(a) for a in nominal.lengths_m)
    return ArmParams(
        lengths_m=lengths,
        masses_kg=tuple(float(m) for m in masses),
        com_along_m=tuple(float(c) for c in coms),
        com_normal_m=(0.0, 0.0),
        inertia_com_kgm2=tuple(
            segment_inertia_kgm2(float(m), float(c), a) for m, c, a in zip(masses, coms, lengths, strict=True)
        ),
        frictionloss_nm=tuple(float(c) for c in friction),
        damping_nms=(0.0, 0.0),
        stiffness_nm_per_rad=(0.0, 0.0),
        springref_rad=(0.0, 0.0),
    )


def mechanical_sine(speed_scale: float = 1.0) -> TrajectorySpec:
    """The paper's 2-segment protocol (``paper_mechanical_arm_cell()``'s): centres (-36.6, 35.8) deg, amplitudes
    5.7 deg, periods (21, 23) s divided by ``speed_scale``, phases (0, pi/2) rad.

    ``speed_scale`` 1 peaks at 0.030 (shoulder) and 0.027 rad/s (elbow), as the paper's; 4 is four times as fast
    (``bsp simulate --subject paper-arm --speed-scale 4``), the same angles in a quarter of the time.
    """
    base = paper_mechanical_arm_cell().trajectory
    assert isinstance(base, TrajectorySpec)
    return base if speed_scale == 1.0 else base.speed_scaled(speed_scale)


__all__ = [
    "PAPER_ARM_COULOMB_NM",
    "mechanical_arm",
    "mechanical_sine",
    "segment_inertia_kgm2",
]
