"""Settings of the stacked identification: the passive model and the validity thresholds."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from bsp_ros.core.identification.joint.activity import ActivitySettings
from bsp_ros.core.identification.joint.emg_activity import EmgSettings
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.placement import chain_placement_sd_m
from bsp_ros.core.identification.priors import BasePrior
from bsp_ros.validation import check_finite_scalar, check_positive


@dataclass(frozen=True, kw_only=True)
class JointConfig:
    """Settings of the stacked identification.

    Attributes
    ----------
    passive : the passive moment model (Coulomb by default).
    deadband_fraction : rows of a joint whose direction speed is below this fraction of its typical speed
        are left out of the fit: there the sign of the motion, hence the Coulomb term, is ambiguous.
    deadband_noise_sd : and rows below this many standard deviations of the velocity noise.
    min_samples : fewer usable samples make the estimate invalid.
    min_range_deg : a joint moving less than this has no excitation (invalid).
    min_direction_share : each direction of motion must hold this share of a joint's rows (Coulomb).
    max_condition : a larger column-scaled condition number makes the estimate invalid.
    check_elastic : test whether an elastic term the model lacks would change the static moments (with the
        other model checks: friction at low speed, a drifting sensor).
    check_drift : run the drift check (and model a drift it finds) also when ``check_elastic`` is False: one
        wider fit, cheap enough for every live update, so a live window models a drift as `bsp identify` does.
    outlier_sd : torque samples further than this many robust standard deviations from the rolling median
        of their neighbours (wrench spikes), or from the fit, are removed.
    spike_window : samples in that rolling median.
    max_misfit : the residual RMS of a joint above this multiple of the sensor noise the data shows
        (robust, from first differences) means the model does not fit: invalid.
    max_outlier_shift : if removing the samples far off the fit moves a parameter by more than this many
        standard deviations, the estimate hangs on a few samples: invalid.
    min_row_share : with a Coulomb term, a joint whose direction of motion is trustworthy in fewer than
        this share of the samples makes the estimate invalid.
    confounded_corr, confounded_rel_std : a passive term is reported confounded with gravity when its
        correlation with a static moment exceeds ``confounded_corr`` and that static moment is uncertain by
        more than ``confounded_rel_std`` of its value: a high correlation alone is harmless when the session
        pins both down (a planned protocol), and the warning says what the confounding costs.
    dynamics : the full rigid-body model: inertial torques of the static moments, perpendicular first
        moments and grouped inertias, the latter two with Gaussian priors (``base_prior``; the default
        subject's anthropometric prior when None), so that what the data cannot tell keeps its prior
        uncertainty in the std instead of being taken as zero.
    marker_placement_sd_m : how far (1 sd, m, per axis) a skin marker may sit from its joint centre: what
        such offsets would move the estimate by joins its covariance (0: markers taken as exact).
    handle_pose_sd_m : the same for the contact point where the robot's handle pose gives it (1 sd, m, per
        axis): the robot's registration to the motion-capture ``world``, not a skin marker's placement.
    elastic_fallback : when the elastic check finds an elastic passive moment the model lacks, identify again
        with the elastic terms chosen by the data (``--passive auto``) instead of returning an invalid estimate:
        what `bsp identify` does when no passive model was asked for.
    check_activity : find stretches where the arm was not relaxed (bursts of muscle activity) and leave them out;
        ``activity`` says how they are told from the relaxed arm, ``emg`` how EMG envelopes tell them where the
        session has them.
    """

    passive: PassiveModel = field(default_factory=PassiveModel)
    deadband_fraction: float = 0.1
    deadband_noise_sd: float = 4.0
    min_samples: int = 200
    min_range_deg: float = 0.2
    min_direction_share: float = 0.05
    max_condition: float = 1e4
    check_elastic: bool = True
    check_drift: bool = False
    outlier_sd: float = 8.0
    spike_window: int = 11
    max_misfit: float = 4.0
    min_row_share: float = 0.5
    max_outlier_shift: float = 2.0
    confounded_corr: float = 0.95
    confounded_rel_std: float = 0.01
    dynamics: bool = True
    base_prior: BasePrior | None = None
    marker_placement_sd_m: float = 0.002
    handle_pose_sd_m: float = 0.0005
    elastic_fallback: bool = False
    check_activity: bool = True
    activity: ActivitySettings = field(default_factory=ActivitySettings)
    emg: EmgSettings = field(default_factory=EmgSettings)

    def __post_init__(self) -> None:
        check_finite_scalar("deadband_fraction", self.deadband_fraction, 0.0, 0.9)
        check_finite_scalar("deadband_noise_sd", self.deadband_noise_sd, 0.0, 100.0)
        check_positive("min_samples", self.min_samples)
        check_finite_scalar("min_range_deg", self.min_range_deg, 0.0, 90.0)
        check_finite_scalar("min_direction_share", self.min_direction_share, 0.0, 0.5)
        check_positive("max_condition", self.max_condition)
        check_positive("outlier_sd", self.outlier_sd, 1000.0)
        check_positive("spike_window", self.spike_window, 10_001)
        check_positive("max_misfit", self.max_misfit)
        check_finite_scalar("min_row_share", self.min_row_share, 0.0, 1.0)
        check_finite_scalar("max_outlier_shift", self.max_outlier_shift, 0.0, 1e6)
        check_finite_scalar("confounded_corr", self.confounded_corr, 0.0, 1.0)
        check_finite_scalar("confounded_rel_std", self.confounded_rel_std, 0.0, 1e6)
        check_finite_scalar("marker_placement_sd_m", self.marker_placement_sd_m, 0.0, 0.05)
        check_finite_scalar("handle_pose_sd_m", self.handle_pose_sd_m, 0.0, 0.05)

    def placement_sd_m(self, n_joints: int, contact_from_robot: bool) -> np.ndarray:
        """(n + 1,) placement sd of each chain point, m (:func:`chain_placement_sd_m`)."""
        return chain_placement_sd_m(n_joints, self.marker_placement_sd_m, self.handle_pose_sd_m, contact_from_robot)
