"""What a plan's sessions will report, by simulation: the static moments' and passive curves' std, skin markers."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from bsp_ros.core.planning.budget import nominal_passive_truth
from bsp_ros.core.planning.choice import AutoChoice
from bsp_ros.core.planning.information import NominalArm
from bsp_ros.core.planning.planner import Plan
from bsp_ros.core.streams import joints_for, segments_for
from bsp_ros.errors import InputError

#: Markers re-placed within this much of the joint centres per recording (uniform per axis), m: a day's placement.
SKIN_BOUND_M = 0.003
#: A passive curve is "followed" when its error is within this share of the curve (RMS over the range) ...
CURVE_TARGET = 0.10
#: ... at this many of its std (RMS over the range): about 95 % of sessions, not two in three. One simulated
#: session's std also varies with the arm and with the model the data choose.
CURVE_CONFIDENCE_STD = 2.0
#: Passive moments of a relaxed arm up to this share of the gravity torque are what a plan must resolve.
REALISTIC_PASSIVE_SHARE = 0.10
#: Recordings of one plan at several trunk tilts are this far apart in time (ns): distinct, as in a cell.
_RECORDING_GAP_NS = 600_000_000_000


@dataclass(frozen=True)
class SimulatedPlanCheck:
    """One simulated session of a plan (one recording per trunk posture), identified as a user would.

    Attributes
    ----------
    model : the passive model identified (the plan's: with ``auto`` the data choose, and the std holds the choice).
    static_moments : segment -> (value, std), kg m; NaN where the simulated estimate could not tell them.
    curve_rms_std_nm : joint -> RMS over the planned range of the passive curve's std, Nm.
    gravity_rms_nm : joint -> RMS of the gravity torque along the plan (first posture), Nm.
    valid : the simulated estimate's verdict; ``message`` its message.
    choice : with ``auto``, the model the data chose and those they could not reject; None for a fixed model.
    """

    model: str
    static_moments: dict[str, tuple[float, float]]
    curve_rms_std_nm: dict[str, float]
    gravity_rms_nm: dict[str, float]
    valid: bool
    message: str
    choice: AutoChoice | None = None

    def smallest_followed_nm(self, joint: str) -> float:
        """The smallest passive moment (RMS, Nm) whose curve the plan follows within :data:`CURVE_TARGET`
        (at :data:`CURVE_CONFIDENCE_STD` of the curve's std)."""
        return CURVE_CONFIDENCE_STD * self.curve_rms_std_nm[joint] / CURVE_TARGET

    def unresolved_joints(self) -> list[str]:
        """Joints where a passive moment of :data:`REALISTIC_PASSIVE_SHARE` of gravity is not followed."""
        return [
            joint
            for joint in self.curve_rms_std_nm
            # Written as "not <=" so that a curve the session could not identify (std inf) counts as unresolved.
            if not self.smallest_followed_nm(joint) <= REALISTIC_PASSIVE_SHARE * self.gravity_rms_nm[joint]
        ]


def plan_cell_spec(
    plan: Plan,
    subject: Any,
    passive: Any,
    *,
    seed: int,
    recording: int = 0,
    tilt_rad: float = 0.0,
    skin_offset_m: tuple[tuple[float, float], ...] = (),
) -> Any:
    """The :class:`~bsp_ros.core.simulation.CellSpec` of one simulated recording of ``plan``: its noise and rates,
    ``passive`` on ``subject``, at trunk tilt ``tilt_rad`` (the same motion relative to the trunk), recording number
    ``recording`` placed after the earlier ones, skin markers at ``skin_offset_m`` (``(along, normal)`` per marker,
    m). A CellSpec of its own: the human cell's defaults are a 3-segment arm, and a plan may be for 2."""
    from bsp_ros.core import simulation as sim

    noise = plan.request.noise
    duration_s = plan.request.duration_s
    return sim.CellSpec(
        subject=subject,
        passive=passive,
        trajectory=sim.TrunkTiltedTrajectory(plan.trajectory, tilt_rad) if tilt_rad else plan.trajectory,
        trunk_tilt_rad=tilt_rad,
        duration_s=duration_s,
        seed=seed,
        start_ns=sim.DEFAULT_START_NS + recording * (round(duration_s * 1e9) + _RECORDING_GAP_NS),
        sensor=sim.SensorSpec(
            force_noise_n=noise.force_noise_n, torque_noise_nm=noise.torque_noise_nm, wrench_hz=noise.wrench_hz
        ),
        markers=sim.MarkerSpec(noise_m=noise.marker_noise_m, marker_hz=noise.marker_hz, skin_offset_m=skin_offset_m),
    )


def _value_std(quantity: dict[str, Any]) -> tuple[float, float]:
    """A quantity's ``(value, std)``; NaN for each that the estimate leaves null (an invalid estimate of data that
    cannot tell it, e.g. a plan whose amplitudes are below the no-motion threshold)."""
    value, std = quantity.get("value"), quantity.get("std")
    return (math.nan if value is None else float(value), math.nan if std is None else float(std))


def simulated_plan_check(
    plan: Plan,
    subject: Any,
    *,
    seed: int = 0,
    skin_bound_m: float = SKIN_BOUND_M,
) -> SimulatedPlanCheck:
    """Simulate ``plan`` once per trunk posture on ``subject`` and identify the recordings together.

    Parameters
    ----------
    plan : the plan (its request gives the noise, the passive model and the trunk tilts).
    subject : the :class:`~bsp_ros.core.simulation.SubjectTruth` simulated (the table arm).
    seed : seed of the simulated sessions (each posture ``seed + k``).
    skin_bound_m : markers placed within this much of the joint centres (one placement for every posture), m.

    The sensor is taken as tared; the simulated arm has the cell's Coulomb friction and nonlinear, coupled elastic
    moments about the middle of the planned motion (:func:`plan_passive_truth`). The passive model identified is
    the plan's own.
    """
    from bsp_ros.core.model import gravity_regressor
    from bsp_ros.core.pipeline import IdentifyOptions, identify_recordings

    request = plan.request
    n = request.nominal.n_joints
    model = request.passive
    t = np.linspace(0.0, plan.trajectory.duration_s, 2001)
    q = plan.trajectory.angles_rad(t)
    sessions = [
        cell.session for cell in simulated_recordings(plan, subject, plan_passive_truth(plan), seed, skin_bound_m)
    ]
    options = IdentifyOptions(passive=model, zero_sd_n=0.0, zero_sd_nm=0.0)
    document = identify_recordings(sessions, options, trunk_tilts_rad=request.trunk_tilts_rad)
    static = {segment: _value_std(q_["static_moment_kgm"]) for segment, q_ in document["segments"].items()}
    beta = np.asarray(subject.static_moments_kgm, dtype=float)
    gravity = np.einsum("kij,j->ki", gravity_regressor(q), beta)
    curves, gravity_rms = {}, {}
    for j, joint in enumerate(joints_for(n)):
        curve = document["joints"].get(joint, {}).get("passive_curve")
        std = np.asarray(curve["std_nm"], dtype=float) if isinstance(curve, dict) else np.array([math.inf])
        curves[joint] = float(np.sqrt(np.mean(std**2)))
        gravity_rms[joint] = float(np.sqrt(np.mean(gravity[:, j] ** 2)))
    quality = document["quality"]
    return SimulatedPlanCheck(
        model=model.label,
        static_moments=static,
        curve_rms_std_nm=curves,
        gravity_rms_nm=gravity_rms,
        valid=bool(quality["valid"]),
        message=str(quality.get("message", "")),
        choice=AutoChoice.from_estimate(document, model) if model.select else None,
    )


def nominal_subject(nominal: NominalArm) -> Any:
    """The :class:`~bsp_ros.core.simulation.SubjectTruth` of the nominal arm: its segment lengths and static
    moments (the de Leva table's centres of mass along each segment, the masses that give those moments), so
    that a simulated session of it has the gravity torques the prediction assumes.

    Raises
    ------
    InputError
        The static moments need a segment of no or negative mass (a hand heavier than its forearm can carry).
    """
    from bsp_ros.core.anthropometry import segment_norm
    from bsp_ros.core.simulation import SubjectTruth

    lengths = np.asarray(nominal.lengths_m)
    beta = np.asarray(nominal.static_moments_kgm)
    com = np.array([segment_norm("male", name).com_fraction for name in segments_for(lengths.size)]) * lengths
    masses = np.zeros(lengths.size)
    # beta_j = m_j l_j + a_j (m_{j+1} + ... + m_n): solved from the hand inward.
    for j in range(lengths.size - 1, -1, -1):
        masses[j] = (beta[j] - lengths[j] * masses[j + 1 :].sum()) / com[j]
    if (masses <= 0).any():
        raise InputError(f"the nominal static moments {beta.round(4).tolist()} kg m imply a segment of no mass")
    return SubjectTruth(tuple(lengths), tuple(masses), tuple(com))


def plan_passive_truth(plan: Plan) -> Any:
    """The simulated arm's passive moments for ``plan``: the cell's Coulomb friction and nonlinear, coupled elastic
    moments (``budget.NOMINAL_STIFFNESS_NM_PER_RAD``, ``NOMINAL_STIFFENING_NM``, ``NOMINAL_BIARTICULAR_NM``) about
    the middle of the planned motion (a
    :class:`~bsp_ros.core.simulation.PassiveTruth`)."""
    return nominal_passive_truth(
        plan.trajectory, plan.trajectory.duration_s, plan.request.nominal.n_joints, elastic=True, nonlinear=True
    )


def simulated_recordings(plan: Plan, subject: Any, passive: Any, seed: int, skin_bound_m: float) -> list[Any]:
    """One simulated recording of ``plan`` per trunk posture (each a ``SimulatedCell``; posture ``k`` seeded
    ``seed + k``) on ``subject`` with ``passive``, its markers placed within ``skin_bound_m`` (m, uniform per axis)
    of the joint centres: one day's placement, kept for every posture (the markers stay on between them)."""
    from bsp_ros.core import simulation as sim

    n = plan.request.nominal.n_joints
    offsets = sim.skin_offsets_m(sim.MarkerSpec(skin_offset_bound_m=skin_bound_m), n + 1, seed)
    return [
        sim.simulate_cell(
            plan_cell_spec(plan, subject, passive, seed=seed + k, recording=k, tilt_rad=tilt, skin_offset_m=offsets)
        )
        for k, tilt in enumerate(plan.request.trunk_tilts_rad)
    ]
