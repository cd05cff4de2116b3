"""scripts/documents_unchanged.py: its comparison of two `bsp identify` documents, and its manifest of bags."""

from __future__ import annotations

import copy
import importlib.util
import json
import sys
from pathlib import Path
from types import ModuleType

import pytest

from bsp_ros.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def script() -> ModuleType:
    spec = importlib.util.spec_from_file_location("documents_unchanged", ROOT / "scripts" / "documents_unchanged.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses resolve their annotations through sys.modules
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def document(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """A real estimate: the sample bag human_arm_60s identified by `bsp identify --json`."""
    out = tmp_path_factory.mktemp("documents") / "estimate.json"
    assert main(["identify", str(ROOT / "bags" / "human_arm_60s"), "--json", str(out), "--format", "none"]) == 0
    return json.loads(out.read_text())


def test_a_document_equal_but_for_a_listed_added_key_is_equal(script: ModuleType, document: dict) -> None:
    new = copy.deepcopy(document)
    new["segments"]["forearm"]["static_moment_kgm"]["budget_note"] = "added"
    new["quality"]["new_block"] = {"a": 1.0}
    new["software"]["version"] = "9.9.9"  # a release, not an answer
    comparison = script.compare_documents(document, new, allowed_added=["budget_note", "/quality/new_*"])
    assert comparison.equal
    assert comparison.changed == comparison.added == ()
    assert sorted(comparison.allowed) == ["/quality/new_block", "/segments/forearm/static_moment_kgm/budget_note"]
    # Not listed: the same addition is a difference.
    unlisted = script.compare_documents(document, new, allowed_added=["budget_note"])
    assert not unlisted.equal and unlisted.added == ("/quality/new_block",)


def test_a_changed_value_is_reported_and_noise_below_the_tolerance_is_not(script: ModuleType, document: dict) -> None:
    value = document["segments"]["forearm"]["static_moment_kgm"]["value"]
    noisy = copy.deepcopy(document)
    noisy["segments"]["forearm"]["static_moment_kgm"]["value"] = value * (1.0 + 1e-12)
    assert script.compare_documents(document, noisy).equal

    changed = copy.deepcopy(document)
    changed["segments"]["forearm"]["static_moment_kgm"]["value"] = value * (1.0 + 1e-6)
    changed["quality"]["valid"] = not document["quality"]["valid"]
    del changed["joints"]["elbow"]
    comparison = script.compare_documents(document, changed)
    assert not comparison.equal
    paths = sorted(line.split(" ")[0] for line in comparison.changed)
    assert paths == ["/joints/elbow", "/quality/valid", "/segments/forearm/static_moment_kgm/value"]
    assert any("(removed)" in line for line in comparison.changed)
    # A looser tolerance takes the 1e-6 change as noise; the flag and the removed joint stay differences.
    loose = script.compare_documents(document, changed, rel_tol=1e-5)
    assert len(loose.changed) == 2


def test_a_list_of_another_length_or_a_number_of_another_kind_is_a_difference(script: ModuleType) -> None:
    assert not script.compare_documents({"a": [1.0, 2.0]}, {"a": [1.0]}).equal
    assert not script.compare_documents({"a": "1.0"}, {"a": 1.0}).equal
    assert not script.compare_documents({"a": True}, {"a": 1}).equal
    assert script.compare_documents({"a": 1}, {"a": 1.0}).equal
    assert script.compare_documents({"a": None}, {"a": None}).equal


def test_the_manifest_holds_ten_or_more_varied_bags_it_can_make(script: ModuleType) -> None:
    cases = script.MANIFEST
    assert len(cases) >= 10
    assert len({c.name for c in cases}) == len(cases)
    kinds = {c.kind for c in cases}
    assert kinds == set(script.Kind)
    for case in cases:
        if case.kind == script.Kind.SAMPLE:
            assert (ROOT / "bags" / case.make[0] / "metadata.yaml").is_file(), case.name
    assert sum(c.kind == script.Kind.MUJOCO for c in cases) == 2
