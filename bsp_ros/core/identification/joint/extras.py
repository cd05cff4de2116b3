"""The rigid-body dynamics blocks of the stacked problem, with their anthropometric priors."""

from __future__ import annotations

import numpy as np

from bsp_ros.core.dynamics import base_regressor
from bsp_ros.core.fusion import SubjectInfo
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.config import JointConfig
from bsp_ros.core.identification.priors import base_prior_for_subject
from bsp_ros.core.identification.stacked import Extras
from bsp_ros.errors import InputError


def base_extras(data: IdentificationData, config: JointConfig) -> Extras | None:
    """The dynamics and perpendicular-moment blocks with their priors, or None when the model is static."""
    if not config.dynamics:
        return None
    n = data.n_joints
    zeros = np.zeros_like(data.q_rad)
    qd = zeros if data.qd_rad_s is None else data.qd_rad_s
    qdd = zeros if data.qdd_rad_s2 is None else data.qdd_rad_s2
    prior = config.base_prior or base_prior_for_subject(SubjectInfo(), data.lengths_m)
    if n != prior.inertia_mean_kgm2.size:
        raise InputError(f"the base prior is for {prior.inertia_mean_kgm2.size} segments, the data has {n}")
    return Extras(base_regressor(data.q_rad, qd, qdd, data.lengths_m), prior)
