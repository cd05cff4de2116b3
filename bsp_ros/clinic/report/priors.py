"""Anthropometric prior bands (de Leva tables) for segment mass and centre of mass, from a session's subject data."""

from __future__ import annotations

from dataclasses import dataclass

from bsp_ros.clinic.store.records import ParamKey, SessionRecord
from bsp_ros.errors import InputError

PRIOR_QUANTITIES = ("mass_kg", "com_m")


@dataclass(frozen=True)
class Prior:
    """A Gaussian prior: the table value for this subject and one standard deviation."""

    mean: float
    std: float


def has_prior_inputs(record: SessionRecord) -> bool:
    """Whether the session records the subject's body mass and sex (what the tables need)."""
    return "body_mass_kg" in record.subject_info and "sex" in record.subject_info


def session_prior(record: SessionRecord, key: ParamKey) -> Prior | None:
    """The table prior of ``key`` for the subject of ``record``, or None if it has none.

    Parameters
    ----------
    record : SessionRecord
        The session; its ``subject_info`` must hold ``body_mass_kg`` and ``sex``.
    key : ParamKey
        A ``("segments", segment, "mass_kg" | "com_m")`` key.

    Returns
    -------
    Prior or None
        None for other quantities, segments outside the tables, a forearm that ends at the contact
        point (a two-segment chain: forearm and hand together are not a table row), or a COM without a
        segment length (neither a measured ``length_m`` nor the subject's height).
    """
    from bsp_ros.core.anthropometry import length_from_height_m, segment_norm

    group, segment, quantity = key
    if group != "segments" or quantity not in PRIOR_QUANTITIES or not has_prior_inputs(record):
        return None
    if segment == "forearm" and not any(part == "hand" for g, part, _ in record.parameters if g == "segments"):
        return None
    sex, body_mass = str(record.subject_info["sex"]), float(record.subject_info["body_mass_kg"])
    try:
        norm = segment_norm(sex, segment)
    except InputError:
        return None
    if quantity == "mass_kg":
        return Prior(body_mass * norm.mass_fraction, body_mass * norm.mass_fraction_sd)
    length = record.parameters.get(("segments", segment, "length_m"))
    if length is not None and length.value is not None and length.value > 0:
        segment_length = length.value
    elif "height_m" in record.subject_info:
        segment_length = length_from_height_m(sex, segment, float(record.subject_info["height_m"]))
    else:
        return None
    return Prior(norm.com_fraction * segment_length, norm.com_fraction_sd * segment_length)
