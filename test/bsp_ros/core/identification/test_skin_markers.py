"""Skin markers re-placed within +-3 mm of the joint centres every session: valid, and the truth within 3 std."""

from __future__ import annotations

import dataclasses
import functools

import pytest

from bsp_ros.core import simulation as sim
from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.pipeline import identify_session
from bsp_ros.core.planning import JointLimits, NominalArm, PlanRequest, plan_protocol
from bsp_ros.core.quantities import quantities_of

BOUND_M = 0.003
DATA_SOURCES = ("data", "data+prior")


@functools.cache
def _planned() -> object:
    nominal = NominalArm.from_anthropometry(sim.human_arm_cell().subject.lengths_m)
    limits = JointLimits(((-70.0, -10.0), (10.0, 100.0), (-20.0, 20.0)))
    return plan_protocol(PlanRequest(nominal=nominal, shoulder_yz_m=(0.0, 1.2), limits=limits)).trajectory


def _session(seed: int, planned: bool) -> sim.SimulatedSession:
    spec = sim.human_arm_cell(seed=seed)
    spec = dataclasses.replace(spec, markers=dataclasses.replace(spec.markers, skin_offset_bound_m=BOUND_M))
    if planned:
        spec = dataclasses.replace(spec, trajectory=_planned())
    return sim.simulate_cell(spec)


def _z(document: dict, truth: dict) -> dict[str, float]:
    out = {}
    for group, owner, key, q in quantities_of(document):
        true = truth[group].get(owner, {}).get(key)
        if q["source"] in DATA_SOURCES and isinstance(true, float) and q["std"]:
            out[f"{key}/{owner}"] = abs(q["value"] - true) / q["std"]
    return out


# Sessions that were INVALID and right before the model checks allowed for the markers' placement: a Stribeck-like
# friction at the shoulder (paper seeds 5, 6), an off-axis hand COM (paper seed 3), a misfit at the wrist (planned
# seed 7); and one that was valid (paper seed 0).
@pytest.mark.parametrize(("seed", "planned"), [(0, False), (3, False), (5, False), (7, True)])
def test_re_placed_markers_give_a_valid_estimate_that_holds_the_truth(seed: int, planned: bool) -> None:
    simulated = _session(seed, planned)
    document = identify_session(simulated.session)
    assert document["quality"]["valid"], document["quality"]["message"]
    z = _z(document, simulated.truth.to_dict())
    assert {"length_m/forearm", "static_moment_kgm/forearm", "coulomb_nm/elbow"} <= set(z)
    assert max(z.values()) <= 3.0, sorted(z.items(), key=lambda kv: -kv[1])[:3]
    # The offsets do not read as a wrench delay (the delay profile fits them beside gravity and friction), nor as
    # low-speed friction or anything else the model lacks: no finding but the prior's, a wider placement, or what
    # the placement's share of the std leaves confounded (the planned seed's hand static moment, 35 %).
    assert document["quality"]["timing"]["wrench_delay_s"] == 0.0
    assert {f["code"] for f in document["quality"]["findings"]} <= {"prior_note", "placement_wider", "confounded"}


def test_a_segment_length_std_holds_the_placement_of_its_two_markers() -> None:
    simulated = _session(4, False)
    document = identify_session(simulated.session)
    truth = simulated.truth.to_dict()
    for segment, quantities in document["segments"].items():
        length = quantities["length_m"]
        assert length["std"] >= 2**0.5 * 0.002  # the default placement sd, 2 mm per marker
        assert abs(length["value"] - truth["segments"][segment]["length_m"]) <= 3 * length["std"]


@functools.cache
def _inertia_plan() -> object:
    """`bsp plan --excite-inertia --max-speed 0.15`'s two sines per joint for the same ranges."""
    from bsp_ros.core.planning import plan_inertia_protocol

    nominal = NominalArm.from_anthropometry(sim.human_arm_cell().subject.lengths_m)
    limits = JointLimits(((-70.0, -10.0), (10.0, 100.0), (-20.0, 20.0)), 0.15)
    return plan_inertia_protocol(PlanRequest(nominal=nominal, shoulder_yz_m=(0.0, 1.2), limits=limits), 0.3).trajectory


@pytest.mark.parametrize("offset_nm", [0.0, 0.5])
def test_on_the_fast_plan_re_placed_markers_are_no_spring_and_a_real_one_is_found(offset_nm: float) -> None:
    """The elastic check tests its spring terms against the std with the markers' placement (as the passive
    selection does): re-placed markers bent the torques like a spring, and on the fast two-sine plan (bench
    coverage.py's fast_inertia_plan, seed 1) a spring the cell lacks was found and a right estimate thrown away
    ("the upper_arm static moment sits at its bound 0"). A real elastic offset of 0.5 Nm at each joint is still found
    (0.2 Nm is not: with an untared sensor the hand's static moment takes it up, within its std)."""
    spec = sim.human_arm_cell(seed=1)
    markers = dataclasses.replace(spec.markers, skin_offset_bound_m=BOUND_M)
    passive = dataclasses.replace(spec.passive, offset_nm=(offset_nm,) * 3)
    spec = dataclasses.replace(spec, markers=markers, passive=passive, trajectory=_inertia_plan())
    simulated = sim.simulate_cell(spec)
    document = identify_session(simulated.session)
    quality = document["quality"]
    found = [f.text for f in findings_of(quality) if f.code is FindingCode.ELASTIC_TERM]
    assert quality["valid"], quality["message"]
    z = _z(document, simulated.truth.to_dict())
    assert max(z.values()) <= 3.0, sorted(z.items(), key=lambda kv: -kv[1])[:3]
    assert bool(found) == (offset_nm > 0), found
