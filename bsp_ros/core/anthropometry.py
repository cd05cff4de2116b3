"""Anthropometric segment tables (de Leva 1996) as Gaussian priors on segment mass and centre of mass."""

from __future__ import annotations

from dataclasses import dataclass

from bsp_ros.errors import InputError
from bsp_ros.validation import check_positive

SEXES = ("male", "female")
# de Leva (1996) stature of the reference populations, m: segment lengths scale with height.
REFERENCE_HEIGHT_M = {"male": 1.741, "female": 1.735}
# Population means used when a subject's body mass is not given (wide: says little about one person).
DEFAULT_BODY_MASS_KG = {"male": 78.0, "female": 65.0}
DEFAULT_BODY_MASS_SD_KG = 15.0


@dataclass(frozen=True)
class SegmentNorm:
    """One segment's table row.

    Attributes
    ----------
    mass_fraction : segment mass / body mass.
    mass_fraction_sd : one standard deviation of that fraction for an individual.
    com_fraction : COM distance from the proximal joint / segment length.
    com_fraction_sd : one standard deviation of that fraction.
    length_m : mean segment length of the reference population.
    gyration_fraction : radius of gyration about the COM for rotation in the sagittal plane (about the
        medio-lateral, "transverse" axis) / segment length.
    """

    mass_fraction: float
    mass_fraction_sd: float
    com_fraction: float
    com_fraction_sd: float
    length_m: float
    gyration_fraction: float = 0.0


# Mass and COM fractions: de Leva 1996 (NOTES.md 2). Spreads: Zatsiorsky-Seluyanov give 9-13 % (1 sd) for
# the population; individuals deviate from tables by up to 40-60 %, so the mass prior is 20 % (1 sd) wide.
# The upper-arm COM direction is disputed (42.3 % vs 57.7 % from the shoulder): its prior is kept wide.
# Radii of gyration: de Leva 1996 Table 4, about the transverse (medio-lateral) axis, the axis of flexion in
# the sagittal plane. Individuals deviate from them like the masses: the inertia prior is wide.
GYRATION_REL_SD = 0.15
_MASS_REL_SD = 0.20
DE_LEVA: dict[str, dict[str, SegmentNorm]] = {
    "male": {
        "upper_arm": SegmentNorm(0.0271, 0.0271 * _MASS_REL_SD, 0.5772, 0.08, 0.2817, 0.269),
        "forearm": SegmentNorm(0.0162, 0.0162 * _MASS_REL_SD, 0.4574, 0.03, 0.2689, 0.265),
        "hand": SegmentNorm(0.0061, 0.0061 * _MASS_REL_SD, 0.7900, 0.05, 0.0862, 0.513),
    },
    "female": {
        "upper_arm": SegmentNorm(0.0255, 0.0255 * _MASS_REL_SD, 0.5754, 0.08, 0.2751, 0.260),
        "forearm": SegmentNorm(0.0138, 0.0138 * _MASS_REL_SD, 0.4559, 0.03, 0.2643, 0.257),
        "hand": SegmentNorm(0.0056, 0.0056 * _MASS_REL_SD, 0.7474, 0.05, 0.0780, 0.454),
    },
}


def check_sex(sex: str) -> str:
    """Return ``sex`` if it is one of the table's populations."""
    if sex not in SEXES:
        raise InputError(f"sex must be one of {SEXES}, got {sex!r}")
    return sex


def check_body_mass_kg(body_mass_kg: float) -> float:
    """Return a plausible adult body mass in kg (20-300)."""
    mass = check_positive("body mass (kg)", body_mass_kg)
    if not 20.0 <= mass <= 300.0:
        raise InputError(f"body mass (kg) must be within [20, 300], got {body_mass_kg!r}")
    return mass


def check_height_m(height_m: float) -> float:
    """Return a plausible adult height in m (1.0-2.5)."""
    height = check_positive("height (m)", height_m)
    if not 1.0 <= height <= 2.5:
        raise InputError(f"height (m) must be within [1.0, 2.5], got {height_m!r}")
    return height


def segment_norm(sex: str, segment: str) -> SegmentNorm:
    """The de Leva row of ``segment`` (``upper_arm``, ``forearm`` or ``hand``) for ``sex``."""
    table = DE_LEVA[check_sex(sex)]
    if segment not in table:
        raise InputError(f"no anthropometric row for segment {segment!r}; known: {tuple(table)}")
    return table[segment]


def length_from_height_m(sex: str, segment: str, height_m: float) -> float:
    """Table segment length (m) scaled to a subject of ``height_m``."""
    return segment_norm(sex, segment).length_m * check_height_m(height_m) / REFERENCE_HEIGHT_M[sex]


def inertia_com_kgm2(sex: str, segment: str, mass_kg: float, length_m: float) -> float:
    """Table moment of inertia (kg m^2) of a segment about its COM, for rotation in the sagittal plane."""
    return mass_kg * (segment_norm(sex, segment).gyration_fraction * length_m) ** 2
