"""A received wrench as the identifiers take it: the tare's load removed, in ``world`` axes, on the angles' clock."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bsp_ros.core.identification.timing import measured_stamps_ns
from bsp_ros.core.tare import Tare
from msg_adapters.wrench import WrenchSample


@dataclass(frozen=True)
class WrenchInput:
    """How the node turns a wrench message into an identifier's sample.

    Attributes
    ----------
    tare : a `bsp tare` of this sensor (its offset and handle load are removed), or None.
    delay_s : how late the wrench stamps are behind the joint states' (``wrench_delay_s``; live applies 0 when it
        is unset), s: applied by :func:`~bsp_ros.core.identification.timing.measured_stamps_ns`, as offline.
    """

    tare: Tare | None = None
    delay_s: float = 0.0

    def world(self, sample: WrenchSample, rotation: np.ndarray) -> tuple[int, np.ndarray] | None:
        """One wrench in ``world``.

        Parameters
        ----------
        sample : the wrench in its sensor frame (N, N m), stamped ns.
        rotation : (3, 3) rotation ``world <- sensor`` at its stamp.

        Returns
        -------
        ``(t_ns, wrench_yzx)``: when it was measured on the joint states' clock, ns, and ``[F_y (N), F_z (N),
        M_x (N m)]`` (3,); None when its frame is not the tare's (that tare does not describe this sensor).
        """
        force_n, torque_nm = sample.force_n, sample.torque_nm
        if self.tare is not None:
            if sample.frame_id != self.tare.frame_id:
                return None
            load_force_n, load_torque_nm = self.tare.predicted_wrench(rotation)
            force_n, torque_nm = force_n - load_force_n, torque_nm - load_torque_nm
        force, torque = rotation @ force_n, rotation @ torque_nm
        return measured_stamps_ns(sample.t_ns, self.delay_s), np.array([force[1], force[2], torque[0]])
