"""The true arm of a simulated cell: segment geometry, masses, inertias (SubjectTruth) and passive moments."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.core.anthropometry import (
    DE_LEVA,
    check_body_mass_kg,
    check_height_m,
    check_sex,
    inertia_com_kgm2,
    length_from_height_m,
    segment_norm,
)
from bsp_ros.core.normalised import normalising
from bsp_ros.core.simulation.checks import (
    MAX_COM_FRACTION,
    MAX_COULOMB_NM,
    MAX_INERTIA_KGM2,
    MAX_LENGTH_M,
    MAX_MASS_KG,
    MAX_OFFSET_NM,
    MAX_STIFFNESS_NM_PER_RAD,
    MAX_VISCOUS_NMS,
    MIN_LENGTH_M,
    check_n_segments,
    float_tuple,
)
from bsp_ros.core.streams import segments_for
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_scalar, check_positive

# The paper's mechanical arm: its segments taken as uniform slender bars of the segment length (the paper
# gives no inertia): I_com = m a^2 / 12. An assumption, recorded with the truth.
PAPER_ARM_INERTIA_ASSUMPTION = "uniform slender bars: I_com = m a^2 / 12 (the paper gives no inertia)"


@normalising
@dataclass(frozen=True)
class SubjectTruth:
    """True segment geometry and mass of a simulated arm (2 or 3 segments, proximal to distal).

    Attributes
    ----------
    lengths_m : (n,) tuple of float
        Segment lengths a_j in m: shoulder->elbow, elbow->wrist, wrist->contact point (a 2-segment
        chain: shoulder->elbow, elbow->contact point).
    masses_kg : (n,) tuple of float
        Segment masses m_j in kg.
    com_m : (n,) tuple of float
        COM distance l_j from the proximal joint along the segment axis, in m.
    inertia_com_kgm2 : (n,) tuple of float
        Moment of inertia about the COM for rotation in the sagittal plane (about x), kg m^2, > 0.
        Empty (the default): ``m_j (k_j a_j)^2`` with the de Leva male radius of gyration fraction
        ``k_j`` of the segment of that name (``bsp_ros.core.anthropometry``).
    com_perpendicular_m : (n,) tuple of float
        The COM's offset normal to the segment axis, m, + toward 90 deg counter-clockwise from the axis
        (|d_j| <= a_j / 2). Empty (the default): on the axis.

    Raises
    ------
    InputError
        If n is not 2 or 3, the tuples differ in length, or a value is non-finite or implausible
        (length outside [0.01, 1] m, mass outside (0, 30] kg, COM outside (0, 1.5 a_j], inertia outside
        (0, 5] kg m^2, perpendicular offset beyond half the length).
    """

    lengths_m: tuple[float, ...]
    masses_kg: tuple[float, ...]
    com_m: tuple[float, ...]
    inertia_com_kgm2: tuple[float, ...] = ()
    com_perpendicular_m: tuple[float, ...] = ()

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: tuples of floats, the empty defaults expanded."""
        lengths = float_tuple("lengths_m", given.lengths_m, None, MIN_LENGTH_M, MAX_LENGTH_M)
        n = check_n_segments(len(lengths), "the number of segments (entries of lengths_m)")
        masses = float_tuple("masses_kg", given.masses_kg, n, positive=True, hi=MAX_MASS_KG)
        coms = float_tuple("com_m", given.com_m, n, positive=True)
        for j, (com, length) in enumerate(zip(coms, lengths, strict=True)):
            if com > MAX_COM_FRACTION * length:
                raise InputError(
                    f"com_m[{j}] = {com!r} m is implausible for a segment of length {length!r} m "
                    f"(at most {MAX_COM_FRACTION} lengths)"
                )
        inertia = given.inertia_com_kgm2
        if isinstance(inertia, Sequence | np.ndarray) and len(inertia) == 0:
            table = DE_LEVA["male"]
            inertia = tuple(
                m * (table[name].gyration_fraction * a) ** 2
                for m, a, name in zip(masses, lengths, segments_for(n), strict=True)
            )
        inertia = float_tuple("inertia_com_kgm2", inertia, n, positive=True, hi=MAX_INERTIA_KGM2)
        perpendicular = given.com_perpendicular_m
        if isinstance(perpendicular, Sequence | np.ndarray) and len(perpendicular) == 0:
            perpendicular = (0.0,) * n
        perpendicular = float_tuple("com_perpendicular_m", perpendicular, n, -MAX_LENGTH_M, MAX_LENGTH_M)
        for j, (d, length) in enumerate(zip(perpendicular, lengths, strict=True)):
            if abs(d) > 0.5 * length:
                raise InputError(
                    f"com_perpendicular_m[{j}] = {d!r} m is implausible for a segment of length {length!r} m "
                    "(at most half a length off the axis)"
                )
        return {
            "lengths_m": lengths,
            "masses_kg": masses,
            "com_m": coms,
            "inertia_com_kgm2": inertia,
            "com_perpendicular_m": perpendicular,
        }

    @property
    def n_segments(self) -> int:
        """Number of segments (2 or 3)."""
        return len(self.lengths_m)

    @property
    def segment_names(self) -> tuple[str, ...]:
        """``upper_arm``, ``forearm`` (, ``hand``)."""
        return segments_for(self.n_segments)

    @property
    def first_moments_kgm(self) -> tuple[float, ...]:
        """(n,) ``m_j l_j`` per segment, kg m."""
        return tuple(m * c for m, c in zip(self.masses_kg, self.com_m, strict=True))

    @property
    def static_moments_kgm(self) -> tuple[float, ...]:
        """(n,) grouped static moments ``beta_j = m_j l_j + a_j * sum_{k>j} m_k`` (docs/contract.md), kg m."""
        out = []
        for j in range(self.n_segments):
            distal_mass = sum(self.masses_kg[j + 1 :])
            out.append(self.masses_kg[j] * self.com_m[j] + self.lengths_m[j] * distal_mass)
        return tuple(out)

    @property
    def perpendicular_moments_kgm(self) -> tuple[float, ...]:
        """(n,) ``m_j d_j``: mass times the COM's offset normal to the segment axis, kg m (0 on the axis)."""
        return tuple(m * d for m, d in zip(self.masses_kg, self.com_perpendicular_m, strict=True))

    @property
    def inertia_kgm2(self) -> tuple[float, ...]:
        """(n,) inertia about the proximal joint ``I_com,j + m_j (l_j^2 + d_j^2)``, kg m^2."""
        return tuple(
            i + m * (c * c + d * d)
            for i, m, c, d in zip(
                self.inertia_com_kgm2, self.masses_kg, self.com_m, self.com_perpendicular_m, strict=True
            )
        )

    @property
    def grouped_inertia_kgm2(self) -> tuple[float, ...]:
        """(n,) identifiable inertia groups ``inertia_kgm2_j + a_j^2 sum_{k>j} m_k``, kg m^2."""
        return tuple(
            self.inertia_kgm2[j] + self.lengths_m[j] ** 2 * sum(self.masses_kg[j + 1 :]) for j in range(self.n_segments)
        )

    @classmethod
    def from_anthropometry(
        cls,
        sex: str = "male",
        body_mass_kg: float = 75.0,
        height_m: float = 1.78,
        n_segments: int = 3,
        rng: np.random.Generator | None = None,
    ) -> SubjectTruth:
        """A subject from the de Leva table (``bsp_ros.core.anthropometry``).

        Lengths are the table lengths scaled with height (the hand: wrist -> 3rd metacarpale, taken as
        wrist -> contact point). Masses are ``mass_fraction * body_mass_kg`` and COM distances
        ``com_fraction * length``, at the table means if ``rng`` is None, else drawn from the table's
        Gaussian prior (fractions clipped to [0.3, 1.7] x mean for mass, [0.2, 0.9] for COM). Inertias
        about the COM are the table's (``anthropometry.inertia_com_kgm2``, de Leva radii of gyration about
        the transverse axis) for the drawn mass and length; COMs lie on the segment axes.

        Parameters
        ----------
        sex : ``"male"`` or ``"female"``.
        body_mass_kg : body mass, kg (20-300).
        height_m : stature, m (1.0-2.5).
        n_segments : 2 (upper arm, forearm) or 3 (plus hand).
        rng : generator for a draw from the prior; None for the table means.

        Returns
        -------
        SubjectTruth
        """
        sex = check_sex(sex)
        body_mass = check_body_mass_kg(body_mass_kg)
        height = check_height_m(height_m)
        n = check_n_segments(n_segments)
        lengths, masses, coms = [], [], []
        for name in segments_for(n):
            norm = segment_norm(sex, name)
            length = length_from_height_m(sex, name, height)
            mass_fraction, com_fraction = norm.mass_fraction, norm.com_fraction
            if rng is not None:
                mass_fraction = float(
                    np.clip(
                        rng.normal(norm.mass_fraction, norm.mass_fraction_sd),
                        0.3 * norm.mass_fraction,
                        1.7 * norm.mass_fraction,
                    )
                )
                com_fraction = float(np.clip(rng.normal(norm.com_fraction, norm.com_fraction_sd), 0.2, 0.9))
            lengths.append(length)
            masses.append(mass_fraction * body_mass)
            coms.append(com_fraction * length)
        inertia = tuple(
            inertia_com_kgm2(sex, name, m, a) for name, m, a in zip(segments_for(n), masses, lengths, strict=True)
        )
        return cls(tuple(lengths), tuple(masses), tuple(coms), inertia)

    @classmethod
    def paper_mechanical_arm(cls) -> SubjectTruth:
        """The method paper's 2-segment mechanical arm (Table 1 CAD values).

        From Table 1: ``m2 l2 = 0.130`` kg m, ``m2 = 1.160`` kg, ``m1 l1 = 0.260`` kg m, so
        ``l2 = 0.130 / 1.160 = 0.1121`` m (the table prints 0.115). **Assumed** (the paper gives no
        values): ``a1 = a2 = 0.30`` m and ``m1 = 1.5`` kg, hence ``l1 = 0.260 / 1.5 = 0.1733`` m, and
        inertias about the COM of uniform slender bars of the segment length, ``m a^2 / 12``
        (``PAPER_ARM_INERTIA_ASSUMPTION``).

        Returns
        -------
        SubjectTruth
        """
        m1, m2 = 1.5, 1.160
        a1 = a2 = 0.30
        return cls(
            lengths_m=(a1, a2),
            masses_kg=(m1, m2),
            com_m=(0.260 / m1, 0.130 / m2),
            inertia_com_kgm2=(m1 * a1 * a1 / 12.0, m2 * a2 * a2 / 12.0),
        )


@normalising
@dataclass(frozen=True, kw_only=True)
class PassiveTruth:
    """True passive joint moment, per joint (shoulder, elbow, wrist), the torque the driver must supply.

    ``tau_p,j = c_j s(qdot_j) h(qdot_j) + b_j qdot_j + k_j (q_j - q0_j) + offset_j`` (Nm), where the
    direction shape ``s(v) = sign(v)`` (``sign(0) = 0``) if ``friction_transition_rad_s`` is 0, else
    ``tanh(v / friction_transition_rad_s)`` (a smooth transition), and the Stribeck-like level
    ``h(v) = 1 + (stribeck_ratio - 1) exp(-(v / stribeck_speed_rad_s)^2)`` (1 for the default ratio 1:
    plain Coulomb; > 1 sticks more at low speed). ``c_j`` is the level at speeds far above both widths.
    An empty tuple (the default for all but ``coulomb_nm``) means zeros for every joint.

    Attributes
    ----------
    coulomb_nm : (n,) Coulomb amplitudes c_j >= 0, Nm.
    viscous_nms : (n,) viscous coefficients b_j >= 0, Nm s/rad.
    stiffness_nm_per_rad : (n,) stiffnesses k_j >= 0, Nm/rad.
    neutral_rad : (n,) neutral angles q0_j of the elastic term, rad (relative joint angles).
    offset_nm : (n,) constant offsets, Nm.
    friction_transition_rad_s : width of the tanh direction transition, rad/s (0: a sign step).
    stribeck_ratio : friction level at zero speed over ``c_j`` (>= 0; 1: no Stribeck effect).
    stribeck_speed_rad_s : speed scale of the Stribeck decay, rad/s (> 0).
    stiffening_nm : (n,) a stiffening elastic moment ``e_j sinh((q_j - q0_j) / w)`` per joint, Nm (the double
        exponential of Riener and Edrich's passive joint moments, centred on the neutral angle; 0: none).
    biarticular_nm : a two-joint muscle across the shoulder and the elbow, Nm: the potential
        ``b w exp((q_1 + q_2 - q_b) / w)`` (``q_1`` to the trunk) gives both joints ``b exp((q_1 + q_2 - q_b) / w)``,
        so the elbow's passive moment depends on the shoulder angle as the method paper says (0: none).
    biarticular_neutral_rad : ``q_b``, rad.
    stiffening_width_rad : ``w`` of both, rad (> 0).
    """

    coulomb_nm: tuple[float, ...]
    viscous_nms: tuple[float, ...] = ()
    stiffness_nm_per_rad: tuple[float, ...] = ()
    neutral_rad: tuple[float, ...] = ()
    offset_nm: tuple[float, ...] = ()
    friction_transition_rad_s: float = 0.0
    stribeck_ratio: float = 1.0
    stribeck_speed_rad_s: float = 0.01
    stiffening_nm: tuple[float, ...] = ()
    biarticular_nm: float = 0.0
    biarticular_neutral_rad: float = 0.0
    stiffening_width_rad: float = 0.5

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments checked, as stored: the numbers as floats, tuples of floats, the empty ones zeros."""
        coulomb = float_tuple("coulomb_nm", given.coulomb_nm, None, 0.0, MAX_COULOMB_NM)
        n = check_n_segments(len(coulomb), "the number of joints (entries of coulomb_nm)")
        bounds = {
            "viscous_nms": (0.0, MAX_VISCOUS_NMS),
            "stiffness_nm_per_rad": (0.0, MAX_STIFFNESS_NM_PER_RAD),
            "neutral_rad": (-2.0 * math.pi, 2.0 * math.pi),
            "offset_nm": (-MAX_OFFSET_NM, MAX_OFFSET_NM),
            "stiffening_nm": (-MAX_OFFSET_NM, MAX_OFFSET_NM),
        }
        out: dict[str, Any] = {"coulomb_nm": coulomb}
        for name, (lo, hi) in bounds.items():
            value = getattr(given, name)
            if isinstance(value, Sequence | np.ndarray) and len(value) == 0:
                value = (0.0,) * n
            out[name] = float_tuple(name, value, n, lo, hi)
        out["friction_transition_rad_s"] = check_finite_scalar(
            "friction_transition_rad_s", given.friction_transition_rad_s, 0.0, 10.0
        )
        out["stribeck_ratio"] = check_finite_scalar("stribeck_ratio", given.stribeck_ratio, 0.0, 10.0)
        out["stribeck_speed_rad_s"] = check_positive("stribeck_speed_rad_s", given.stribeck_speed_rad_s, 10.0)
        for name, (lo, hi) in (
            ("biarticular_nm", (-MAX_OFFSET_NM, MAX_OFFSET_NM)),
            ("biarticular_neutral_rad", (-2.0 * math.pi, 2.0 * math.pi)),
        ):
            out[name] = check_finite_scalar(name, getattr(given, name), lo, hi)
        out["stiffening_width_rad"] = check_positive("stiffening_width_rad", given.stiffening_width_rad, 10.0)
        return out

    @property
    def n_joints(self) -> int:
        """Number of joints (2 or 3)."""
        return len(self.coulomb_nm)

    def elastic_nm(self, q_rad: npt.ArrayLike) -> np.ndarray:
        """Elastic part of the passive moment (offset, stiffness, stiffening, the two-joint muscle): (N, n) joint
        angles, the shoulder's to the trunk, rad -> (N, n) Nm."""
        q = np.atleast_2d(np.asarray(q_rad, dtype=np.float64))
        deviation = q - np.asarray(self.neutral_rad)
        out = (
            np.asarray(self.stiffness_nm_per_rad) * deviation
            + np.asarray(self.offset_nm)
            + np.asarray(self.stiffening_nm) * np.sinh(deviation / self.stiffening_width_rad)
        )
        if self.biarticular_nm:
            stretch = (q[:, 0] + q[:, 1] - self.biarticular_neutral_rad) / self.stiffening_width_rad
            out[:, :2] += self.biarticular_nm * np.exp(stretch)[:, None]
        return out

    def friction_nm(self, qdot_rad_s: npt.ArrayLike) -> np.ndarray:
        """Friction part ``c_j s(qdot_j) h(qdot_j)`` of the passive moment: (N, n) rad/s -> (N, n) Nm."""
        v = np.asarray(qdot_rad_s, dtype=np.float64)
        width = self.friction_transition_rad_s
        shape = np.sign(v) if width == 0.0 else np.tanh(v / width)
        level = 1.0 + (self.stribeck_ratio - 1.0) * np.exp(-((v / self.stribeck_speed_rad_s) ** 2))
        return np.asarray(self.coulomb_nm) * shape * level
