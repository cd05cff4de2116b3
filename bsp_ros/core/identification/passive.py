"""Passive joint moment models: which terms, their columns in the regressor, their names and bounds."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.errors import InputError

# Term -> (parameter key in the estimate, unit, lower bound). The passive moment is what the driver must
# supply beside gravity (CONTRACT.md): Coulomb c sign(qdot), viscous b qdot, elastic k q + offset.
TERMS = {
    "coulomb": ("coulomb_nm", "Nm", 0.0),
    "viscous": ("viscous_nms", "Nm s/rad", 0.0),
    "offset": ("offset_nm", "Nm", -np.inf),
    "stiffness": ("stiffness_nm_per_rad", "Nm/rad", 0.0),
}


@dataclass(frozen=True)
class PassiveModel:
    """A passive moment model: a tuple of terms out of ``coulomb``, ``viscous``, ``offset``, ``stiffness``."""

    terms: tuple[str, ...] = ("coulomb",)

    def __post_init__(self) -> None:
        unknown = [term for term in self.terms if term not in TERMS]
        if unknown or not self.terms or len(set(self.terms)) != len(self.terms):
            raise InputError(f"passive model terms must be distinct names out of {tuple(TERMS)}, got {self.terms}")
        if "stiffness" in self.terms and "offset" not in self.terms:
            # k (q - q0) = k q - k q0: a stiffness without its offset forces the neutral angle to q = 0.
            raise InputError("a stiffness term needs an offset term too (passive model 'coulomb+offset+stiffness')")

    @classmethod
    def parse(cls, text: str) -> PassiveModel:
        """``"coulomb+viscous"`` -> ``PassiveModel(("coulomb", "viscous"))``."""
        return cls(tuple(part.strip() for part in text.split("+") if part.strip()))

    @property
    def label(self) -> str:
        """The ``+``-joined term names."""
        return "+".join(self.terms)

    def columns(self, q_rad: np.ndarray, velocity_rad_s: np.ndarray, joint: int) -> np.ndarray:
        """Regressor columns of one joint's passive terms: (N, n_terms)."""
        q = q_rad[:, joint]
        v = velocity_rad_s[:, joint]
        table = {"coulomb": np.sign(v), "viscous": v, "offset": np.ones_like(q), "stiffness": q}
        return np.column_stack([table[term] for term in self.terms])

    def row_one(self, q_rad: float, velocity_rad_s: float) -> list[float]:
        """One joint's passive columns at one instant, as floats (the 1 kHz live filter's fast path)."""
        sign = (velocity_rad_s > 0) - (velocity_rad_s < 0)
        table = {"coulomb": float(sign), "viscous": velocity_rad_s, "offset": 1.0, "stiffness": q_rad}
        return [table[term] for term in self.terms]
