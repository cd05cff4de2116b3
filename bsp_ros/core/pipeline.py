"""One call from a session's streams to the estimate document: angles, identification, prior fusion."""

from __future__ import annotations

import contextlib
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from bsp_ros.core.contact_point import chain_markers
from bsp_ros.core.estimate import estimate_from_fit, estimate_from_result
from bsp_ros.core.estimate_blocks import TimingBlock
from bsp_ros.core.estimate_schema import Estimate, Quality
from bsp_ros.core.findings import Finding, FindingCode, note
from bsp_ros.core.fusion import (
    Posterior,
    SubjectInfo,
    anthropometric_prior,
    fuse_static_moments,
    implausible_static_moments,
)
from bsp_ros.core.identification.data import IdentificationData, identification_data_from_session
from bsp_ros.core.identification.joint import JointConfig, identify_joint
from bsp_ros.core.identification.joint.held import HeldModel
from bsp_ros.core.identification.joint.refit import refit_held
from bsp_ros.core.identification.paper import PaperConfig, identify_paper
from bsp_ros.core.identification.passive import PassiveModel
from bsp_ros.core.identification.placement import chain_placement_sd_m
from bsp_ros.core.identification.priors import base_prior_for_subject
from bsp_ros.core.identification.rate import identification_rate_hz
from bsp_ros.core.identification.recordings import combine_recordings
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.identification.sensitivity import account_for_tare
from bsp_ros.core.identification.timing import WrenchDelay, compensate_wrench_delay
from bsp_ros.core.joint_angles import KinematicsConfig, MarkerKinematics, kinematics_from_markers
from bsp_ros.core.methods import OFFLINE_METHODS, Method
from bsp_ros.core.sensor_rotation import rotation_block
from bsp_ros.core.sensor_zero import ZERO_SD_N, ZERO_SD_NM
from bsp_ros.core.streams import Session
from bsp_ros.core.tare import Tare, corrected_session
from bsp_ros.errors import BspError, InputError

# The offline methods' words (`bsp identify --method`), as the CLI's parser spells them.
METHODS = tuple(m.value for m in OFFLINE_METHODS)


@dataclass(frozen=True, kw_only=True)
class IdentifyOptions:
    """Everything `bsp identify` can be told about the method and the subject."""

    method: Method = Method.JOINT
    passive: PassiveModel = field(default_factory=PassiveModel)
    subject: SubjectInfo = field(default_factory=SubjectInfo)
    kinematics: KinematicsConfig = field(default_factory=KinematicsConfig)
    tare: Tare | None = None
    marker_placement_sd_m: float = 0.002
    # The contact point's placement sd where the robot's handle pose gives it (its registration to `world`), m.
    handle_pose_sd_m: float = 0.0005
    # Stream timing (timing.py): a wrench delay the cell knows (s), or None to estimate it from the data.
    wrench_delay_s: float | None = None
    # Where the data show an elastic passive moment the model lacks, let the data choose the elastic terms
    # (`--passive auto`) instead of returning an invalid estimate: the default when no model was asked for.
    elastic_fallback: bool = True
    # Without a tare, the sensor's zero is assumed within these (1 SD per sensor axis): in the std (sensitivity.py).
    zero_sd_n: float = ZERO_SD_N
    zero_sd_nm: float = ZERO_SD_NM

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            from bsp_ros.errors import InputError

            raise InputError(f"method must be one of {METHODS}, got {self.method!r}")

    def config(self) -> dict[str, Any]:
        """The settings as a JSON-ready dict (kept with each stored session)."""
        return {
            "method": self.method,
            "passive": self.passive.label,
            "elastic_fallback": self.elastic_fallback,
            "angle_cutoff_hz": self.kinematics.cutoff_hz,
            "direction_cutoff_hz": self.kinematics.direction_cutoff_hz,
            "max_gap_s": self.kinematics.max_gap_s,
            "marker_placement_sd_m": self.marker_placement_sd_m,
            "handle_pose_sd_m": self.handle_pose_sd_m,
            "zero_sd_n": self.zero_sd_n,
            "zero_sd_nm": self.zero_sd_nm,
        }

    def placement_sd_m(self, data: IdentificationData) -> np.ndarray:
        """(n + 1,) placement sd of each chain point of ``data``, m (:func:`chain_placement_sd_m`)."""
        return chain_placement_sd_m(
            data.n_joints, self.marker_placement_sd_m, self.handle_pose_sd_m, data.contact_from_robot
        )

    def placement_sd_used_m(self, result: IdentificationResult, data: IdentificationData) -> np.ndarray:
        """(n + 1,) the placement sd ``result``'s std holds, m: the stacked method's (as assumed, or wider where the
        data put the markers further off: ``placement_scale``), else :meth:`placement_sd_m`."""
        return result.held.placement_sd_m if result.held is not None else self.placement_sd_m(data)


def identify_data(
    data: IdentificationData,
    options: IdentifyOptions,
    check_elastic: bool = True,
    check_drift: bool = False,
    held: HeldModel | None = None,
) -> IdentificationResult:
    """Run the chosen identification method on prepared samples.

    ``check_elastic`` runs the model checks (an unmodelled elastic passive term, friction at low speed, a
    drifting sensor; several fits): a live window may run them on only some updates. ``check_drift`` runs
    the drift check (one fit) without the others. ``held`` (the stacked method) refits what an earlier
    identification of the same arm with its checks chose instead (:func:`refit_held`: one fit), as a live window
    does between its checks. A valid result whose static moments are implausible for a human arm
    (:func:`bsp_ros.core.fusion.implausible_static_moments`) is made invalid.
    """
    if options.method == Method.PAPER:
        result = identify_paper(data, PaperConfig())
    else:
        config = JointConfig(
            passive=options.passive,
            check_elastic=check_elastic,
            check_drift=check_drift,
            base_prior=base_prior_for_subject(options.subject, data.lengths_m),
            marker_placement_sd_m=options.marker_placement_sd_m,
            handle_pose_sd_m=options.handle_pose_sd_m,
            elastic_fallback=options.elastic_fallback,
        )
        result = identify_joint(data, config) if held is None else refit_held(data, held, config)
    if result.valid:
        _, beta, beta_cov = result.block("static_moment_kgm")
        std = np.sqrt(np.clip(np.diag(beta_cov), 0.0, None))
        implausible = implausible_static_moments(options.subject, data.lengths_m, beta, beta_std_kgm=std)
        result = result.with_findings(*implausible, first=True)
    return result


def refit_options(result: IdentificationResult, options: IdentifyOptions) -> IdentifyOptions:
    """The options that refit ``result``'s own model (finite differences, sensitivities): the passive model the
    estimate used, fixed. With ``--passive auto`` or the elastic fallback a refit could otherwise choose another
    model than the estimate's, with other parameters."""
    used = result.diagnostics.get("passive_model")
    passive = PassiveModel.parse(used) if isinstance(used, str) and used else options.passive
    return replace(options, passive=passive, elastic_fallback=False)


def fuse(result: IdentificationResult, data: IdentificationData, subject: SubjectInfo) -> Posterior | None:
    """Masses and COMs from the prior and the identified static moments; None if they are not usable."""
    return fused(result, data, subject)[0]


def fused(
    result: IdentificationResult, data: IdentificationData, subject: SubjectInfo
) -> tuple[Posterior | None, IdentificationResult]:
    """:func:`fuse`, and ``result`` with a finding where the fusion failed (a numerical failure, not the data's)."""
    return fused_on_lengths(result, data.lengths_m, subject)


def fused_on_lengths(
    result: IdentificationResult, lengths_m: np.ndarray, subject: SubjectInfo
) -> tuple[Posterior | None, IdentificationResult]:
    """:func:`fused` for segment lengths ``lengths_m`` (n,) m, without the samples (the recursive filter's)."""
    _, beta, beta_cov = result.block("static_moment_kgm")
    if not (np.isfinite(beta).all() and np.isfinite(beta_cov).all()):
        return None, result
    try:
        prior = anthropometric_prior(subject, lengths_m)
        return fuse_static_moments(prior, lengths_m, beta, beta_cov), result
    except (np.linalg.LinAlgError, ValueError) as error:
        failed = Finding(code=FindingCode.FUSION_FAILED, values={"error": str(error)})
        return None, result.with_findings(failed)


def recursive_estimate(
    result: IdentificationResult, lengths_m: np.ndarray, options: IdentifyOptions, contact_from_robot: bool = False
) -> Estimate:
    """The estimate of the recursive filter's ``result`` on segment lengths ``lengths_m`` (n,) m, fused with the
    anthropometric prior when valid, assembled as every other (:func:`estimate_from_result`): the lengths' std is
    the markers' placement alone; ``contact_from_robot``: the contact point came from the robot's handle pose (its
    placement sd)."""
    posterior, result = fused_on_lengths(result, lengths_m, options.subject) if result.valid else (None, result)
    placement_sd_m = chain_placement_sd_m(
        lengths_m.size, options.marker_placement_sd_m, options.handle_pose_sd_m, contact_from_robot
    )
    return estimate_from_result(
        result,
        lengths_m=lengths_m,
        posterior=posterior,
        subject=options.subject,
        placement_sd_m=placement_sd_m,
        contact_from_robot=contact_from_robot,
    )


def identify_session(
    session: Session, options: IdentifyOptions | None = None, session_info: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Identify a whole session; return the docs/contract.md estimate document.

    Raises
    ------
    BspError
        The streams cannot give any estimate (no overlap, missing markers); poor excitation is not an
        error but ``quality.valid`` False.
    """
    return identify_recordings([session], options, session_info=session_info)


def identify_recordings(
    sessions: Sequence[Session],
    options: IdentifyOptions | None = None,
    trunk_tilts_rad: Sequence[float] | None = None,
    session_info: dict[str, Any] | None = None,
    recording_info: Sequence[dict[str, Any]] | None = None,
) -> dict[str, Any]:
    """The docs/contract.md document of :func:`estimate_recordings` (its ``to_json()``)."""
    return estimate_recordings(sessions, options, trunk_tilts_rad, session_info, recording_info).to_json()


def estimate_recordings(
    sessions: Sequence[Session],
    options: IdentifyOptions | None = None,
    trunk_tilts_rad: Sequence[float] | None = None,
    session_info: dict[str, Any] | None = None,
    recording_info: Sequence[dict[str, Any]] | None = None,
) -> Estimate:
    """Identify one arm from one or more recordings, each with its trunk's tilt; the typed estimate.

    Each recording is corrected (tare, stream delay) and turned into samples on its own; the samples are
    then identified together (:func:`combine_recordings`). With several recordings the estimate's
    ``session.recordings`` lists them (``recording_info`` adds to each entry) and ``quality.timing`` gives
    each recording's stream timing.

    Raises
    ------
    BspError
        As :func:`identify_session`; InputError for recordings that are not of one arm and sensor.
    """
    options = options or IdentifyOptions()
    tilts = [0.0] * len(sessions) if trunk_tilts_rad is None else [float(t) for t in trunk_tilts_rad]
    frames = sorted({s.wrench.frame_id for s in sessions})
    if len(frames) > 1:
        raise InputError(f"the recordings' wrenches are in different frames ({', '.join(frames)}): not one sensor")
    prepared = [_prepared(session, options) for session in sessions]
    recordings = [p.data for p in prepared]
    data = combine_recordings(recordings, tilts)
    result = identify_data(data, options)
    refit = refit_options(result, options)
    rotations = [np.asarray(p.session.rotation_world_from_sensor, dtype=np.float64) for p in prepared]
    rotation = rotations[0] if len(rotations) == 1 else np.concatenate([r.reshape(-1, 3, 3) for r in rotations])
    result, offsets = account_for_tare(
        result,
        data,
        rotation,
        prepared[0].session.wrench.frame_id,
        options.tare,
        lambda d: identify_data(d, refit, check_elastic=False),
        (options.zero_sd_n, options.zero_sd_nm),
    )
    posterior, result = fused(result, data, options.subject) if result.valid else (None, result)
    info = _session_info(data, options, session_info)
    if len(sessions) > 1:
        info["recordings"] = [
            {
                "start_time_ns": int(r.t_ns[0]),
                "end_time_ns": int(r.t_ns[-1]),
                "samples": int(r.t_ns.size),
                "trunk_tilt_deg": float(np.degrees(tilt)),
                **(recording_info[k] if recording_info else {}),
            }
            for k, (r, tilt) in enumerate(zip(recordings, tilts, strict=True))
        ]
    estimate = estimate_from_fit(
        result,
        data,
        posterior=posterior,
        subject=options.subject,
        placement_sd_m=options.placement_sd_used_m(result, data),
        session=info,
    )
    quality = _with_timing_and_rotation(offsets.applied_to(estimate.quality), [p.timing for p in prepared], rotation)
    return estimate.with_quality(quality)


@dataclass(frozen=True, kw_only=True)
class _Prepared:
    """One recording corrected (tare, stream delay) and turned into samples."""

    session: Session
    timing: WrenchDelay
    data: IdentificationData


def _prepared(session: Session, options: IdentifyOptions) -> _Prepared:
    """``session`` corrected by the tare and the wrench stamps' delay (timing.py), and its samples."""
    session = corrected_session(session, options.tare)
    # The markers' angles once: the delay search and the identification data share them (where they fail, the
    # identification data says why, in its own order of checks).
    kinematics: MarkerKinematics | None = None
    with contextlib.suppress(BspError):
        kinematics = kinematics_from_markers(chain_markers(session), session.n_segments, options.kinematics)
    session, timing = compensate_wrench_delay(
        session, options.wrench_delay_s, options.kinematics, options.passive, kinematics=kinematics
    )
    data = identification_data_from_session(session, options.kinematics, kinematics)
    return _Prepared(session=session, timing=timing, data=data)


def _session_info(
    data: IdentificationData, options: IdentifyOptions, session_info: dict[str, Any] | None
) -> dict[str, Any]:
    """The estimate's ``session`` block: its span, rates, method and settings, and what the caller adds."""
    return {
        "start_time_ns": int(data.t_ns[0]),
        "end_time_ns": int(data.t_ns[-1]),
        "duration_s": float(data.t_ns[-1] - data.t_ns[0]) / 1e9,
        "n_wrench_samples": data.n_wrench_samples,
        "identification_rate_hz": identification_rate_hz(data.t_ns),
        "method": options.method,
        "config": options.config(),
        **(session_info or {}),
    }


def _with_timing_and_rotation(quality: Quality, timings: Sequence[WrenchDelay], rotation: np.ndarray) -> Quality:
    """``quality`` with the stream timing of each recording and the sensor rotation's shape (timing.py,
    sensor_rotation.py); the timing's notes as findings."""
    quality = quality.with_timing(TimingBlock(recordings=tuple(t.block() for t in timings)))
    for delay in timings:
        for text in delay.warnings:
            if text not in quality.warnings:
                quality = quality.with_finding(note(FindingCode.TIMING_NOTE, text))
    return quality.with_rotation(rotation_block(rotation, "session"))


__all__ = [
    "METHODS",
    "BspError",
    "IdentifyOptions",
    "estimate_recordings",
    "fuse",
    "fused",
    "fused_on_lengths",
    "identify_data",
    "identify_recordings",
    "identify_session",
    "recursive_estimate",
]
