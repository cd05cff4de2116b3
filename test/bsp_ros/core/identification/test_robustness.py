"""One glitched frame, wrench spikes or an absurd sample must not move any parameter beyond its std."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from bsp_ros.core import glitches
from bsp_ros.core.findings import Finding, FindingCode, findings_of
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.pipeline import identify_session
from bsp_ros.core.simulation import SimulatedSession, human_arm_cell, simulate_cell
from bsp_ros.core.streams import Session


@pytest.fixture(scope="module")
def simulated() -> SimulatedSession:
    """60 s of the human arm cell: 3000 marker frames, 6000 wrench samples."""
    return simulate_cell(human_arm_cell(duration_s=60.0, seed=3))


@pytest.fixture(scope="module")
def clean(simulated: SimulatedSession) -> dict[str, Any]:
    return identify_session(simulated.session)


def parameters(document: dict[str, Any]) -> dict[str, tuple[float, float]]:
    out = {}
    for group in ("segments", "joints"):
        for owner, quantities in document[group].items():
            for key, q in quantities.items():
                if q["source"] == "data":
                    out[f"{key}/{owner}"] = (q["value"], q["std"])
    return out


def assert_within_3_std_of(clean: dict[str, Any], glitched: dict[str, Any]) -> None:
    assert glitched["quality"]["valid"], glitched["quality"]["message"]
    want, got = parameters(clean), parameters(glitched)
    assert set(want) == set(got)
    for name, (value, std) in want.items():
        assert abs(got[name][0] - value) < 3 * std, (name, got[name], (value, std))


def _data_note(said: str) -> Callable[[Finding], bool]:
    """Whether a finding is the data layer's note (its text verbatim, it has no code of its own) saying ``said``."""
    return lambda f: f.code is FindingCode.DATA_NOTE and said in f.values["detail"]


# Each glitch and the finding that counts it.
GLITCHES = {
    "swapped elbow and hand": (
        lambda s: glitches.swap_markers(s, "elbow", "hand", 1500),
        _data_note("removed 2 marker frames inconsistent with the rigid chain (elbow 1, hand 1)"),
    ),
    "elbow 0.67 m off": (
        lambda s: glitches.displace_marker(s, "elbow", 1500, (0.0, 0.67, 0.0)),
        _data_note("removed 1 marker frame inconsistent with the rigid chain (elbow)"),
    ),
    "hand jumps 6 cm": (
        lambda s: glitches.displace_marker(s, "hand", 900, (0.0, 0.0, 0.06)),
        _data_note("removed 1 marker frame inconsistent with the rigid chain (hand)"),
    ),
    "ten 1 kN spikes": (
        lambda s: glitches.wrench_spikes(s, 10, 1000.0, seed=1),
        lambda f: f.code is FindingCode.WRENCH_SPIKES_REMOVED and f.values["n"] == 10,
    ),
    "1e30 N": (
        lambda s: glitches.set_wrench_sample(s, 1000, 1e30, 2),
        _data_note("wrench: removed 1 samples with an absurd magnitude"),
    ),
}


@pytest.mark.parametrize("name", list(GLITCHES))
def test_a_glitch_leaves_every_parameter_within_3_std_and_is_counted(
    name: str, simulated: SimulatedSession, clean: dict[str, Any]
) -> None:
    glitch, counted = GLITCHES[name]
    document = identify_session(glitch(simulated.session))
    assert_within_3_std_of(clean, document)
    assert any(counted(f) for f in findings_of(document["quality"])), document["quality"]["findings"]
    assert document["quality"]["removed_samples"]


def test_one_glitched_frame_does_not_inflate_the_velocity_noise(simulated: SimulatedSession) -> None:
    before = identification_data_from_session(simulated.session).velocity_noise_rad_s
    # Bypass the rigid-chain check: the noise estimate itself must be robust.
    glitched = glitches.displace_marker(simulated.session, "elbow", 1500, (0.0, 0.67, 0.0))
    from bsp_ros.core.joint_angles import KinematicsConfig

    loose = KinematicsConfig(max_length_error_m=1.0, outlier_sd=1000.0)
    after = identification_data_from_session(glitched, loose).velocity_noise_rad_s
    np.testing.assert_allclose(after, before, rtol=0.1)


def test_a_wrench_in_the_wrong_frame_fails_the_fit_check(simulated: SimulatedSession) -> None:
    """The rotated sensor read as if aligned with world (a lost transform): never valid."""
    session = simulated.session
    unrotated = Session(session.wrench, session.markers, np.eye(3))
    document = identify_session(unrotated)
    quality = document["quality"]
    assert not quality["valid"]
    codes = [f.code for f in findings_of(quality)]
    assert FindingCode.MODEL_MISFIT in codes and FindingCode.STATIC_MOMENT_AT_BOUND in codes, quality["message"]


def test_implausible_static_moments_are_invalid(simulated: SimulatedSession) -> None:
    """A wrench scaled by 10 (a wrong calibration) fits perfectly, but no arm is that heavy."""
    session = simulated.session
    w = session.wrench
    heavy = Session(
        type(w)(w.t_ns, w.force_n * 10.0, w.torque_nm * 10.0, w.frame_id),
        session.markers,
        session.rotation_world_from_sensor,
    )
    quality = identify_session(heavy)["quality"]
    codes = [f.code for f in findings_of(quality)]
    assert not quality["valid"] and FindingCode.STATIC_MOMENT_IMPLAUSIBLE in codes, quality["message"]
