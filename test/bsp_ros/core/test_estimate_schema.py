"""The typed estimate: an exact JSON round trip, what it keeps of keys it does not type, and what it gives."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.bag.offline import identify_bag
from bsp_ros.core.estimate_schema import Estimate, Level, Quantity, Source
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.methods import LiveMode, Method
from bsp_ros.core.weight_support import support_inputs

SAMPLES = Path(__file__).resolve().parents[3] / "bags"


@pytest.fixture(scope="module")
def document() -> dict:
    """The estimate of the sample human bag, as JSON carries it."""
    return json.loads(json.dumps(identify_bag(SAMPLES / "human_arm_60s")))


def test_the_json_round_trip_is_exact_key_order_included(document: dict) -> None:
    estimate = Estimate.from_json(document)
    assert json.dumps(estimate.to_json()) == json.dumps(document)
    assert estimate.valid and estimate.quality.level is Level.OK and estimate.extra == {}
    assert estimate.bag is not None and estimate.quality.tare is not None  # typed blocks, not extra
    assert estimate.method is Method.JOINT and estimate.mode is None  # an offline estimate has no live mode


def test_quantities_and_the_verdict_are_typed(document: dict) -> None:
    estimate = Estimate.from_json(document)
    forearm = estimate.quantity("static_moment_kgm", "forearm")
    assert forearm is not None and forearm.source is Source.DATA and forearm.finite
    assert forearm.value == document["segments"]["forearm"]["static_moment_kgm"]["value"]
    term, share = forearm.largest_term() or ("", 0.0)
    assert term == max(forearm.budget or {}, key=lambda t: (forearm.budget or {})[t]) and 0.0 < share <= 1.0
    elbow = estimate.quantity("coulomb_nm", "elbow")
    assert elbow is not None and elbow.budget is not None
    assert estimate.quality.tare_applied is False and estimate.quality.verdict is None


def test_an_invalid_live_estimate_names_its_cause() -> None:
    waiting = Finding(code=FindingCode.INPUT_WAITING, values={"what": "wrench"})
    document = Estimate.invalid(Method.JOINT, waiting).to_json()
    document["mode"] = "windowed"
    estimate = Estimate.from_json(document)
    assert not estimate.valid and estimate.quality.verdict is not None
    assert estimate.quality.verdict.code is FindingCode.INPUT_WAITING and estimate.extra == {"mode": "windowed"}
    assert estimate.mode is LiveMode.WINDOWED and estimate.method is Method.JOINT
    assert json.dumps(estimate.to_json()) == json.dumps(document)
    # The typed operation writes the same document as the key set by hand.
    typed = Estimate.invalid(Method.JOINT, estimate.quality.verdict).with_mode(LiveMode.WINDOWED)
    assert json.dumps(typed.to_json()) == json.dumps(document)


def test_the_method_and_the_mode_are_closed_vocabularies_whose_json_is_their_word(document: dict) -> None:
    paper = Estimate.from_json({**document, "method": "paper"})
    assert paper.method is Method.PAPER and json.loads(json.dumps(paper.to_json()))["method"] == "paper"
    assert Estimate.from_json({k: v for k, v in document.items() if k != "method"}).method is Method.JOINT
    with pytest.raises(ValueError, match="stacked"):
        Estimate.from_json({**document, "method": "stacked"})
    recursive = Estimate.from_json(document).with_mode(LiveMode.RECURSIVE)
    assert json.dumps(recursive.to_json()).endswith('"mode": "recursive"}')


def test_an_older_document_and_a_newer_one_keep_what_they_hold(document: dict) -> None:
    older = json.loads(json.dumps(document))
    del older["quality"]["findings"]
    older["quality"]["from_a_newer_version"] = {"x": 1}
    older["future_block"] = [1, 2]
    estimate = Estimate.from_json(older)
    assert estimate.quality.findings == () and estimate.quality.message == document["quality"]["message"]
    again = estimate.to_json()
    assert again["quality"]["from_a_newer_version"] == {"x": 1} and again["future_block"] == [1, 2]
    assert again["quality"]["findings"] == []  # the typed form always has the key
    assert Quantity.from_json({"value": None, "std": None, "source": "prior"}).finite is False


def test_the_weight_support_takes_the_static_moments_and_their_covariance(document: dict) -> None:
    support = support_inputs(Estimate.from_json(document))
    assert support is not None and support["valid"]
    std = [document["segments"][s]["static_moment_kgm"]["std"] for s in ("upper_arm", "forearm", "hand")]
    np.testing.assert_allclose(np.sqrt(np.diag(support["covariance"])), std, rtol=1e-12)
    assert np.all(np.linalg.eigvalsh(support["covariance"]) > -1e-12)
