"""One assembly of the estimate: the recursive filter's estimate is made by the function every other path uses, and
the typed operations that follow it add findings as the contract says."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
import pytest

import bsp_ros.core.estimate as estimate_module
import bsp_ros.core.pipeline as pipeline
from bsp_ros.core import simulation as sim
from bsp_ros.core.estimate import estimate_from_result
from bsp_ros.core.estimate_schema import Estimate, Level
from bsp_ros.core.findings import Finding, FindingCode, note
from bsp_ros.core.identification.data import identification_data_from_session
from bsp_ros.core.identification.placement import chain_placement_sd_m
from bsp_ros.core.identification.recursive import RecursiveConfig, RecursiveIdentifier
from bsp_ros.core.pipeline import IdentifyOptions, fused_on_lengths, recursive_estimate


@pytest.fixture(scope="module")
def session() -> sim.SimulatedSession:
    """A simulated 60 s session of a human arm with known parameters (seeded)."""
    return sim.simulate_cell(sim.human_arm_cell(duration_s=60.0, seed=11))


@pytest.fixture(scope="module")
def filtered(session: sim.SimulatedSession) -> tuple[Any, np.ndarray]:
    """The recursive filter run over the session's samples (as the live feed folds them), and the lengths."""
    data = identification_data_from_session(session.session)
    identifier = RecursiveIdentifier(3, RecursiveConfig())
    identifier.update_many(list(zip(data.t_ns.tolist(), data.q_rad, data.velocity_rad_s, data.tau_nm, strict=True)))
    return identifier.result(), data.lengths_m


def _spy(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Count the calls of the one assembly function, wherever a path reaches it."""
    calls: list[str] = []
    original = estimate_module.estimate_from_result

    def counted(*args: Any, **kwargs: Any) -> Estimate:
        calls.append(args[0].method)
        return original(*args, **kwargs)

    monkeypatch.setattr(estimate_module, "estimate_from_result", counted)
    monkeypatch.setattr(pipeline, "estimate_from_result", counted)
    return calls


def test_the_recursive_estimate_is_assembled_by_the_one_function(
    filtered: tuple[Any, np.ndarray], session: sim.SimulatedSession, monkeypatch: pytest.MonkeyPatch
) -> None:
    result, lengths = filtered
    options = IdentifyOptions()
    calls = _spy(monkeypatch)
    recursive = recursive_estimate(result, lengths, options)
    assert calls == ["recursive"]
    posterior, fused = fused_on_lengths(result, lengths, options.subject)
    placement = chain_placement_sd_m(3, options.marker_placement_sd_m, options.handle_pose_sd_m, False)
    direct = estimate_from_result(
        fused, lengths_m=lengths, posterior=posterior, subject=options.subject, placement_sd_m=placement
    )
    assert json.dumps(recursive.to_json()) == json.dumps(direct.to_json())
    # What the filter found is the simulated arm's: each static moment within 3 std of the truth.
    assert recursive.valid and recursive.quality.level is Level.OK, recursive.quality.message
    for segment, truth in zip(("upper_arm", "forearm", "hand"), session.truth.static_moments_kgm, strict=True):
        q = recursive.quantity("static_moment_kgm", segment)
        assert q is not None and q.value is not None and q.std is not None
        assert abs(q.value - truth) < 3 * q.std, (segment, q, truth)
    # The lengths' std is the markers' placement alone (the filter has no lengths' spread), masses are fused.
    hand = recursive.quantity("length_m", "hand")
    assert hand is not None and hand.std == pytest.approx(np.hypot(0.002, 0.002))
    assert recursive.quality.extra["contact_point"] == "hand_marker" and recursive.session is None
    assert all(recursive.quantity("mass_kg", s) is not None for s in ("upper_arm", "forearm", "hand"))


def test_the_offline_estimate_is_assembled_by_the_same_function(
    session: sim.SimulatedSession, monkeypatch: pytest.MonkeyPatch
) -> None:
    calls = _spy(monkeypatch)
    estimate = pipeline.estimate_recordings([session.session], IdentifyOptions())
    assert calls == ["joint"] and estimate.session is not None
    quality = estimate.quality
    assert quality.timing is not None and quality.rotation is not None and quality.tare is not None
    assert quality.rotation.sources == ("session",)  # a session read from no bag: the pipeline's own word


def test_findings_join_a_typed_estimate_as_the_contract_orders_them() -> None:
    waiting = Estimate.invalid("joint", Finding(code=FindingCode.INPUT_WAITING, values={"what": "markers"}))
    assert waiting.to_json()["quality"]["n_samples"] == 0 and waiting.quality.level is Level.INVALID
    lost = Finding(code=FindingCode.ROTATION_ASSUMED, values={"frame": "ft_sensor"})
    both = waiting.with_findings(note(FindingCode.BAG_NOTE, "first"), note(FindingCode.BAG_NOTE, "second"), at=0)
    both = both.with_findings(lost)
    assert both.quality.warnings == ("first", "second")
    assert [f.code for f in both.quality.findings] == [
        FindingCode.ROTATION_ASSUMED,
        FindingCode.INPUT_WAITING,
        FindingCode.BAG_NOTE,
        FindingCode.BAG_NOTE,
    ]
    assert both.quality.message == f"{lost.text}; waiting for markers" and not both.valid
    assert waiting.quality.findings == (waiting.quality.verdict,)  # the original is left as it was
    assert both.with_extra({"mode": "windowed"}).to_json()["mode"] == "windowed"
