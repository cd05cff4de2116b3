"""Passive joint moment models: which terms, their columns in the regressor, their names and bounds."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from bsp_ros.errors import InputError

# Term -> (parameter key in the estimate, unit, lower bound). The passive moment is what the driver must
# supply beside gravity (docs/contract.md): Coulomb c sign(qdot), viscous b qdot, elastic k q + offset.
TERMS = {
    "coulomb": ("coulomb_nm", "Nm", 0.0),
    "viscous": ("viscous_nms", "Nm s/rad", 0.0),
    "offset": ("offset_nm", "Nm", -np.inf),
    "stiffness": ("stiffness_nm_per_rad", "Nm/rad", 0.0),
}
# Elastic terms beyond a linear spring (bsp_ros.core.identification.elastic): a moment nonlinear in the joint's
# own angle, and the stiffness shared with the proximal joint (two-joint muscles). Both need the linear spring.
# ``higher`` extends ``nonlinear`` (and ``coupling``) by the elastic potential's next order: not chosen by
# ``auto``, it probes how far a nonlinear model's estimate hangs on the assumed shape (selection.shape_probe).
ELASTIC_TERMS = ("nonlinear", "coupling", "higher")
# What `--passive auto` chooses among, beside the base terms: the elastic family, nested.
AUTO = "auto"
AUTO_FAMILY = (
    (),
    ("offset", "stiffness"),
    ("offset", "stiffness", "coupling"),
    ("offset", "stiffness", "nonlinear"),
    ("offset", "stiffness", "coupling", "nonlinear"),
)


@dataclass(frozen=True)
class PassiveModel:
    """A passive moment model: terms out of ``coulomb``, ``viscous``, ``offset``, ``stiffness``, ``nonlinear``,
    ``coupling``; with ``select`` the data choose the elastic terms among :data:`AUTO_FAMILY` (``--passive auto``)
    and the estimate's std holds what that choice leaves uncertain."""

    terms: tuple[str, ...] = ("coulomb",)
    select: bool = False

    def __post_init__(self) -> None:
        known = (*TERMS, *ELASTIC_TERMS)
        unknown = [term for term in self.terms if term not in known]
        if unknown or not self.terms or len(set(self.terms)) != len(self.terms):
            raise InputError(
                f"passive model terms must be distinct names out of {known} joined by '+', or '{AUTO}', "
                f"got {self.terms}"
            )
        if "stiffness" in self.terms and "offset" not in self.terms:
            # k (q - q0) = k q - k q0: a stiffness without its offset forces the neutral angle to q = 0.
            raise InputError("a stiffness term needs an offset term too (passive model 'coulomb+offset+stiffness')")
        for term in ELASTIC_TERMS:
            if term in self.terms and "stiffness" not in self.terms:
                raise InputError(f"a {term} term extends the linear spring: it needs 'offset+stiffness' too")
        if "higher" in self.terms and "nonlinear" not in self.terms:
            raise InputError("a higher term extends the nonlinear one: it needs 'nonlinear' too")
        if not any(term in ("coulomb", "viscous", "offset") for term in self.terms):
            raise InputError(f"a passive model needs 'coulomb', 'viscous' or 'offset', got {'+'.join(self.terms)}")

    @classmethod
    def parse(cls, text: str) -> PassiveModel:
        """``"coulomb+viscous"`` -> ``PassiveModel(("coulomb", "viscous"))``; ``"auto"`` -> Coulomb friction with
        the elastic terms chosen by the data."""
        parts = [part.strip() for part in text.split("+") if part.strip()]
        if parts == [AUTO]:
            return cls(("coulomb",), select=True)
        return cls(tuple(parts))

    @property
    def label(self) -> str:
        """The ``+``-joined term names (``auto`` when the data choose)."""
        return AUTO if self.select else "+".join(self.terms)

    @functools.cached_property
    def local(self) -> tuple[str, ...]:
        """The terms with one column per joint in that joint's row (:data:`TERMS`); kept (the 1 kHz live filter
        asks for them with every row)."""
        return tuple(term for term in self.terms if term in TERMS)

    def local_column(self, term: str, n_joints: int, joint: int) -> int:
        """The stacked problem's column of the local ``term`` of joint ``joint`` (0-based) in a chain of
        ``n_joints``: after the static moments, each joint's local terms in turn (:func:`build_problem`)."""
        return n_joints + joint * len(self.local) + self.local.index(term)

    @property
    def elastic(self) -> tuple[str, ...]:
        """The elastic terms beyond a linear spring (:data:`ELASTIC_TERMS`)."""
        return tuple(term for term in self.terms if term in ELASTIC_TERMS)

    def with_terms(self, extra: tuple[str, ...]) -> PassiveModel:
        """This model's terms plus ``extra`` (in family order), a fixed model."""
        order = (*TERMS, *ELASTIC_TERMS)
        terms = tuple(term for term in order if term in self.terms or term in extra)
        return PassiveModel(terms)

    def candidates(self) -> list[PassiveModel]:
        """The models ``--passive auto`` chooses among: these terms with each set of :data:`AUTO_FAMILY`."""
        out: list[PassiveModel] = []
        for extra in AUTO_FAMILY:
            model = self.with_terms(extra)
            if model not in out:
                out.append(model)
        return out

    def columns(self, q_rad: np.ndarray, velocity_rad_s: np.ndarray, joint: int) -> np.ndarray:
        """Regressor columns of one joint's local passive terms: (N, n_local)."""
        q = q_rad[:, joint]
        v = velocity_rad_s[:, joint]
        table = {"coulomb": np.sign(v), "viscous": v, "offset": np.ones_like(q), "stiffness": q}
        return np.column_stack([table[term] for term in self.local])

    def row_one(self, q_rad: float, velocity_rad_s: float) -> list[float]:
        """One joint's local passive columns at one instant, as floats (the 1 kHz live filter's fast path)."""
        sign = (velocity_rad_s > 0) - (velocity_rad_s < 0)
        table = {"coulomb": float(sign), "viscous": velocity_rad_s, "offset": 1.0, "stiffness": q_rad}
        return [table[term] for term in self.local]
