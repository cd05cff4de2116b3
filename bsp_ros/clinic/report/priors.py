"""Anthropometric prior bands (de Leva tables) for segment mass and centre of mass, from a session's subject data."""

from __future__ import annotations

from dataclasses import dataclass

from bsp_ros.clinic.store.records import ParamKey, SessionRecord
from bsp_ros.errors import InputError

PRIOR_QUANTITIES = ("mass_kg", "com_m", "static_moment_kgm")
PRIOR_SOURCE = "de Leva (1996)"
"""The anthropometric tables the priors come from (bsp_ros.core.anthropometry)."""


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

    The static moment's prior is the tables' ``m c + l (sum of the distal masses)`` about the segment's proximal
    joint, its SD propagated from the masses' and centres of mass's (:func:`static_moment_prior`).

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
    if quantity == "static_moment_kgm":
        return static_moment_prior(record, segment)
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


def _chain_lengths(record: SessionRecord) -> list[float] | None:
    """The measured lengths of the chain's segments from the upper arm on (None if one is missing)."""
    from bsp_ros.core.anthropometry import length_from_height_m
    from bsp_ros.core.streams import segments_for

    present = {part for group, part, _ in record.parameters if group == "segments"}
    chain = [s for s in segments_for(3) if s in present]
    if chain != list(segments_for(len(chain))) or len(chain) < 3:
        return None
    lengths = []
    for segment in chain:
        quantity = record.parameters.get(("segments", segment, "length_m"))
        if quantity is not None and quantity.value is not None and quantity.value > 0:
            lengths.append(quantity.value)
        elif "height_m" in record.subject_info:
            lengths.append(
                length_from_height_m(str(record.subject_info["sex"]), segment, float(record.subject_info["height_m"]))
            )
        else:
            return None
    return lengths


def static_moment_prior(record: SessionRecord, segment: str) -> Prior | None:
    """The tables' static moment of ``segment`` about its proximal joint for the subject of ``record``.

    ``s_i = m_i c_i + l_i (m_{i+1} + ... + m_n)`` at the tables' masses and centres of mass (de Leva 1996, for
    the subject's sex and body mass, the centres scaled to the measured lengths); its SD is the population's,
    propagated to first order through :func:`bsp_ros.core.fusion.anthropometric_prior`'s covariance. None for
    a chain that is not upper arm, forearm and hand (the tables have no row for a forearm with the hand).
    """
    import numpy as np

    from bsp_ros.core.fusion import SubjectInfo, anthropometric_prior
    from bsp_ros.core.streams import segments_for

    lengths = _chain_lengths(record)
    if lengths is None:
        return None
    chain = list(segments_for(len(lengths)))
    if segment not in chain:
        return None
    info = SubjectInfo(float(record.subject_info["body_mass_kg"]), None, str(record.subject_info["sex"]))
    prior = anthropometric_prior(info, np.asarray(lengths))
    n, i = len(chain), chain.index(segment)
    masses, coms = prior.mean[:n], prior.mean[n:]
    jacobian = np.zeros(2 * n)
    jacobian[i], jacobian[n + i] = coms[i], masses[i]
    jacobian[i + 1 : n] = lengths[i]
    mean = masses[i] * coms[i] + lengths[i] * float(np.sum(masses[i + 1 :]))
    return Prior(float(mean), float(np.sqrt(jacobian @ prior.covariance @ jacobian)))


@dataclass(frozen=True)
class PeerRow:
    """One segment quantity of one arm against its table prediction: ``z`` in population SDs."""

    key: ParamKey
    label: str
    value: float
    std: float
    prior: Prior
    session: int

    @property
    def z(self) -> float:
        """``(value - table) / population SD``."""
        return (self.value - self.prior.mean) / self.prior.std

    @property
    def words(self) -> str:
        """``typical``, ``heavier than most`` (1 to 2 SD) or ``far heavier than most`` (beyond 2 SD); a value
        measured less precisely than twice the population's SD is not compared."""
        if self.std > 2.0 * self.prior.std:
            return "measured too roughly to compare with peers"
        z = self.z
        if abs(z) < 1.0:
            return "typical for this body"
        side = "heavier" if z > 0 else "lighter"
        return f"{side} than most" if abs(z) < 2.0 else f"far {side} than most (beyond the usual range)"
