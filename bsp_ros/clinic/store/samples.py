"""Synthetic but schema-valid `bsp_ros/core/estimate/1` dicts, for tests, demos and trying the store."""

from __future__ import annotations

import random
from collections.abc import Iterable, Mapping
from typing import Any

from bsp_ros.clinic.store.records import ParamKey
from bsp_ros.core.quantities import quantities_of

# (length m, mass kg, COM distance m) of a typical adult arm.
_SEGMENTS = {"upper_arm": (0.30, 2.1, 0.17), "forearm": (0.27, 1.25, 0.12), "hand": (0.08, 0.45, 0.06)}
_JOINTS = {"upper_arm": "shoulder", "forearm": "elbow", "hand": "wrist"}
_COULOMB_NM = {"shoulder": 0.8, "elbow": 0.35, "wrist": 0.1}
SAMPLE_START_NS = 1_717_225_200 * 10**9  # 2024-06-01T07:00:00Z


def sample_estimate(
    seed: int = 0,
    *,
    segments: Iterable[str] = ("upper_arm", "forearm", "hand"),
    start_time_ns: int | None = SAMPLE_START_NS,
    source: str | None = "session.mcap",
    method: str | None = "static-ols",
    config: Mapping[str, Any] | None = None,
    subject: Mapping[str, Any] | None = None,
    valid: bool = True,
    warnings: Iterable[str] = (),
    overrides: Mapping[ParamKey, tuple[float | None, float | None]] | None = None,
    rel_std: float = 0.03,
    sem_rel: float | None = None,
) -> dict[str, Any]:
    """Build a valid estimate dict.

    Parameters
    ----------
    seed : int
        Seeds small (within one std) deviations of every value, so sessions differ.
    segments : iterable of str
        Segments of the chain, proximal first; ``("upper_arm", "forearm")`` is the two-segment arm.
    start_time_ns, source, method : optional
        The ``session`` block's fields; None leaves a field out (and no block if all are None).
    config : Mapping, optional
        ``session.config``.
    subject : Mapping, optional
        The ``subject`` block (``body_mass_kg``, ``height_m``, ``sex``); None leaves it out.
    valid, warnings :
        The ``quality`` flags.
    overrides : Mapping, optional
        ``(group, part, quantity) -> (value, std)``; may add quantities (e.g. ``viscous_nms``).
    rel_std : float
        Standard deviation relative to the value.
    sem_rel : float, optional
        Adds a ``repeatability`` block: SEM of every ``data`` quantity = ``sem_rel`` x its value.

    Returns
    -------
    dict
        The estimate, ready for ``json.dump``.
    """
    rng = random.Random(seed)
    chain = list(segments)
    segment_blocks, joint_blocks = _chain_blocks(chain, rng, rel_std)
    estimate: dict[str, Any] = {"schema": "bsp_ros/core/estimate/1", "segments": segment_blocks, "joints": joint_blocks}
    for (group, part, name), (value, std) in (overrides or {}).items():
        estimate[group].setdefault(part, {})[name] = {"value": value, "std": std, "source": "data"}
    estimate["quality"] = {
        "valid": valid,
        "n_samples": 12_000 + seed,
        "condition_number": 35.0 + seed % 7,
        "residual_rms_nm": {_JOINTS[s]: 0.05 + 0.001 * (seed % 5) for s in chain},
        "warnings": list(warnings),
    }
    session = _session_block(start_time_ns, source, method, config)
    if session:
        estimate["session"] = session
    if subject is not None:
        estimate["subject"] = dict(subject)
    if sem_rel is not None:
        estimate["repeatability"] = _repeatability_block(estimate, sem_rel)
    return estimate


def _chain_blocks(
    chain: list[str], rng: random.Random, rel_std: float
) -> tuple[dict[str, dict[str, Any]], dict[str, dict[str, Any]]]:
    """The ``segments`` and ``joints`` blocks of a typical adult arm, each value within ``rel_std`` of the table.

    Parameters
    ----------
    chain : segment names, proximal first.
    rng : draws every segment's mass, then every COM, then each joint's Coulomb amplitude, in that order.
    rel_std : deviation bound and standard deviation, relative to the value.

    Returns
    -------
    The segments' quantities (length m, static moment kg m, mass kg, COM m, first moment kg m) and each segment's
    proximal joint's Coulomb amplitude (Nm).
    """
    lengths = {s: _SEGMENTS[s][0] for s in chain}
    masses = {s: _SEGMENTS[s][1] * (1 + rel_std * rng.uniform(-1, 1)) for s in chain}
    coms = {s: _SEGMENTS[s][2] * (1 + rel_std * rng.uniform(-1, 1)) for s in chain}

    def quantity(value: float, source: str = "data") -> dict[str, Any]:
        return {"value": value, "std": abs(value) * rel_std, "source": source}

    segment_blocks: dict[str, dict[str, Any]] = {}
    joint_blocks: dict[str, dict[str, Any]] = {}
    for i, name in enumerate(chain):
        distal_mass = sum(masses[s] for s in chain[i + 1 :])
        segment_blocks[name] = {
            "length_m": quantity(lengths[name], "prior"),
            "static_moment_kgm": quantity(masses[name] * coms[name] + lengths[name] * distal_mass),
            "mass_kg": quantity(masses[name], "data+prior"),
            "com_m": quantity(coms[name], "data+prior"),
            "first_moment_kgm": quantity(masses[name] * coms[name], "data+prior"),
        }
        joint = _JOINTS[name]
        coulomb = _COULOMB_NM[joint] * (1 + rel_std * rng.uniform(-1, 1))
        joint_blocks[joint] = {"coulomb_nm": quantity(coulomb)}
    return segment_blocks, joint_blocks


def _session_block(
    start_time_ns: int | None, source: str | None, method: str | None, config: Mapping[str, Any] | None
) -> dict[str, Any]:
    """The ``session`` block: the fields that are not None (``start_time_ns`` in ns), and ``config`` if given."""
    fields = {"start_time_ns": start_time_ns, "source": source, "method": method}
    session: dict[str, Any] = {k: v for k, v in fields.items() if v is not None}
    if config is not None:
        session["config"] = dict(config)
    return session


def _repeatability_block(estimate: dict[str, Any], sem_rel: float) -> dict[str, Any]:
    """A ``repeatability`` block: the SEM of every finite ``data`` quantity is ``sem_rel`` times its value."""
    return {
        "method": "sample: SEM set to a fixed fraction of each value",
        "n_cycles": 5,
        "n_valid_cycles": 5,
        "parameters": {
            f"{group}.{part}.{name}": {"sem": abs(q["value"]) * sem_rel, "n": 5}
            for group, part, name, q in quantities_of(estimate)
            if q["source"] == "data" and isinstance(q["value"], float) and q["value"] == q["value"]
        },
    }
