"""``geometry_msgs/msg/InertiaStamped`` <-> numpy."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from msg_adapters._types import TypeLookup
from msg_adapters.stamps import build_header, read_header
from msg_adapters.wrench import build_vector3, read_vector3


@dataclass(frozen=True)
class InertiaSample:
    """One stamped rigid-body inertia.

    Attributes
    ----------
    t_ns : header stamp in nanoseconds.
    frame_id : ``header.frame_id``.
    mass_kg : mass in kg.
    com_m : (3,) float64, centre of mass in m.
    inertia_kgm2 : (3, 3) float64 symmetric inertia tensor about the centre of mass, kg m^2.
    """

    t_ns: int
    frame_id: str
    mass_kg: float
    com_m: np.ndarray
    inertia_kgm2: np.ndarray


def read_inertia_stamped(msg: Any) -> InertiaSample:
    """Read an ``InertiaStamped`` into an :class:`InertiaSample`."""
    t_ns, frame_id = read_header(msg.header)
    i = msg.inertia
    tensor = np.array([[i.ixx, i.ixy, i.ixz], [i.ixy, i.iyy, i.iyz], [i.ixz, i.iyz, i.izz]], dtype=np.float64)
    return InertiaSample(t_ns, frame_id, float(i.m), read_vector3(i.com), tensor)


def build_inertia_stamped(types: TypeLookup, sample: InertiaSample) -> Any:
    """Build a ``geometry_msgs/msg/InertiaStamped`` (upper triangle of the tensor is used).

    Raises
    ------
    ValueError
        If the inertia tensor is not (3, 3).
    """
    t = np.asarray(sample.inertia_kgm2, dtype=np.float64)
    if t.shape != (3, 3):
        raise ValueError(f"inertia tensor must have shape (3, 3), got {t.shape}")
    inertia = types("geometry_msgs/msg/Inertia")(
        m=float(sample.mass_kg),
        com=build_vector3(types, sample.com_m),
        ixx=float(t[0, 0]),
        ixy=float(t[0, 1]),
        ixz=float(t[0, 2]),
        iyy=float(t[1, 1]),
        iyz=float(t[1, 2]),
        izz=float(t[2, 2]),
    )
    return types("geometry_msgs/msg/InertiaStamped")(
        header=build_header(types, sample.t_ns, sample.frame_id), inertia=inertia
    )
