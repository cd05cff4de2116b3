"""A static moment held at its bound 0 pushes what the data put below it into its segment's off-axis moment: judged
on the data's own fit, and the push joins the covariance, on a simulated session with known parameters."""

from __future__ import annotations

import numpy as np

from bsp_ros.core import simulation as sim
from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.pipeline import IdentifyOptions, identify_session

SEGMENTS = ("upper_arm", "forearm", "hand")


def _session(contact_normal_mm: float) -> tuple[dict, np.ndarray]:
    """40 s of the paper's sines at half the simulator's rates, a light hand, the contact marker off the hand's
    axis by ``contact_normal_mm`` (the other markers on their centres)."""
    spec = sim.human_arm_cell(
        sex="male",
        body_mass_kg=82.0,
        height_m=1.80,
        passive=sim.PassiveTruth(coulomb_nm=(0.6, 0.35, 0.08), stiffness_nm_per_rad=(0.0, 1.0, 0.0)),
        markers=sim.MarkerSpec(skin_offset_m=((0, 0), (0, 0), (0, 0), (0, contact_normal_mm / 1e3)), marker_hz=25.0),
        sensor=sim.SensorSpec(wrench_hz=50.0),
        duration_s=40.0,
        seed=2,
    )
    simulated = sim.simulate_cell(spec)
    options = IdentifyOptions(
        passive=PassiveModel.parse("coulomb+offset+stiffness"), subject=SubjectInfo(82.0, 1.80, "male")
    )
    return identify_session(simulated.session, options, {"source": "bound.mcap"}), simulated.truth.static_moments_kgm


def test_an_off_axis_moment_the_bound_pushed_is_not_read_as_a_missing_one() -> None:
    # 1.5 mm of the contact marker off the hand's axis puts the hand's own static moment below 0: held at 0, its
    # segment's off-axis moment took 0.0067 kg m, 5 std of what the check allows (the estimate was invalid).
    document, truth = _session(1.5)
    quality, hand = document["quality"], document["segments"]["hand"]
    assert quality["valid"], quality["message"]
    assert "perpendicular_implausible" not in [f["code"] for f in quality["findings"]]
    assert hand["static_moment_kgm"]["value"] == 0.0
    for segment, value in zip(SEGMENTS, truth, strict=True):
        moment = document["segments"][segment]["static_moment_kgm"]
        assert abs(moment["value"] - value) < 3.0 * moment["std"], segment
    # The simulated hand has its centre of mass on its axis: the pushed off-axis moment within its std.
    perpendicular = hand["perpendicular_moment_kgm"]
    assert "static_moment_bound" in perpendicular["budget"]
    assert abs(perpendicular["value"]) < 2.0 * perpendicular["std"]
    assert perpendicular["budget"]["static_moment_bound"] > 0.5 * abs(perpendicular["value"])


def test_markers_on_their_centres_add_no_bound_term() -> None:
    document, _ = _session(0.0)
    assert document["quality"]["valid"]
    for segment in SEGMENTS:
        assert "static_moment_bound" not in document["segments"][segment]["static_moment_kgm"].get("budget", {})
