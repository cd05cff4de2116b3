"""The estimate as ROS message samples: passive curves reach bsp/passive_moments and bsp/diagnostics."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.pipeline import IdentifyOptions, identify_session
from bsp_ros.live.estimate_messages import diagnostics_from_estimate, passive_moments_from_estimate


@pytest.fixture(scope="module")
def spring_estimate() -> dict:
    """`--passive auto` on 30 s of our simulator's arm with springs at the shoulder and elbow."""
    passive = sim.PassiveTruth(
        coulomb_nm=(0.5, 0.28, 0.06), stiffness_nm_per_rad=(0.3, 0.5, 0.0), offset_nm=(0.1, 0.2, 0.0)
    )
    simulated = sim.simulate_cell(sim.human_arm_cell(seed=6, duration_s=30.0, passive=passive))
    document = identify_session(simulated.session, IdentifyOptions(passive=PassiveModel.parse("auto")))
    assert document["quality"]["valid"], document["quality"]["message"]
    return document


def test_passive_moments_carry_the_coulomb_amplitudes_then_every_curve_point(spring_estimate: dict) -> None:
    sample = passive_moments_from_estimate(Estimate.from_json(spring_estimate), 7)
    assert sample is not None
    joints = spring_estimate["joints"]
    curves = {j: q["passive_curve"] for j, q in joints.items() if "passive_curve" in q}
    assert "elbow" in curves
    n = len(joints)
    assert sample.names[:n] == tuple(joints)
    assert sample.effort[:n].tolist() == [q["coulomb_nm"]["value"] for q in joints.values()]
    assert np.isnan(sample.position[:n]).all()  # a Coulomb amplitude has no angle
    k = n
    for joint, curve in curves.items():
        points = len(curve["angle_deg"])
        assert sample.names[k : k + points] == tuple(f"{joint}/passive_curve/{i}" for i in range(points))
        assert sample.position[k : k + points] == pytest.approx(np.radians(curve["angle_deg"]))
        assert sample.effort[k : k + points].tolist() == curve["moment_nm"]
        k += points
    assert k == len(sample.names) == sample.position.size == sample.effort.size
    # The elbow spring of the simulator (0.2 Nm + 0.5 Nm/rad from 0) within 3 std at every published point.
    elbow = curves["elbow"]
    truth = 0.2 + 0.5 * np.radians(elbow["angle_deg"])
    assert np.all(np.abs(np.array(elbow["moment_nm"]) - truth) <= 3 * np.array(elbow["std_nm"]))


def test_an_estimate_without_curves_publishes_efforts_only(spring_estimate: dict) -> None:
    estimate = Estimate.from_json(spring_estimate)
    assert estimate.passive_curves
    sample = passive_moments_from_estimate(replace(estimate, passive_curves={}), 7)
    assert sample is not None and sample.position.size == 0 and sample.effort.size == len(estimate.joints)


def test_diagnostics_hold_the_curve_with_its_std(spring_estimate: dict) -> None:
    array = diagnostics_from_estimate(Estimate.from_json(spring_estimate), 7)
    elbow = dict(next(s for s in array.status if s.name == "bsp/elbow").values)
    curve = spring_estimate["joints"]["elbow"]["passive_curve"]
    for k, (angle, moment, std) in enumerate(zip(curve["angle_deg"], curve["moment_nm"], curve["std_nm"], strict=True)):
        assert float(elbow[f"passive_curve.{k}.angle_deg"]) == angle
        assert float(elbow[f"passive_curve.{k}.moment_nm"]) == moment
        assert float(elbow[f"passive_curve.{k}.std_nm"]) == std
    assert float(elbow["passive_curve.stiffness_nm_per_rad"]) == curve["stiffness_nm_per_rad"]
    assert math.isfinite(float(elbow["coulomb_nm.std"]))
