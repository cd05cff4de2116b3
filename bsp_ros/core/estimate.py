"""The one assembly of an :class:`~bsp_ros.core.estimate_schema.Estimate` from an identification and a fused prior.

:func:`estimate_from_result` builds the typed estimate for every path (a recorded session, a live window, the
recursive filter); what is known only later (the tare's share, the stream timing, what a bag read found) is added
with the Estimate's own typed operations, and JSON is written only where a document leaves (``to_json()``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from bsp_ros import __version__
from bsp_ros.core.contact_point import CONTACT_FROM_MARKER, CONTACT_FROM_ROBOT
from bsp_ros.core.estimate_blocks import PlacementBlock
from bsp_ros.core.estimate_schema import Estimate, Level, Quality, Quantity, Source
from bsp_ros.core.findings import FindingCode, note
from bsp_ros.core.fusion import Posterior, SubjectInfo
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.joint.speed_split import speed_dependence_block
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.streams import joints_for, segments_for


def quantity(value: float, std: float, source: str) -> Quantity:
    """One docs/contract.md quantity; a value that could not be computed is None (``null``), never NaN."""
    return Quantity(value=_clean(value), std=_clean(std), source=Source(source))


def estimate_from_result(
    result: IdentificationResult,
    *,
    lengths_m: np.ndarray,
    posterior: Posterior | None,
    subject: SubjectInfo,
    lengths_std_m: np.ndarray | None = None,
    placement_sd_m: float | np.ndarray = 0.0,
    contact_from_robot: bool = False,
    removed_samples: Mapping[str, int] | None = None,
    session: Mapping[str, Any] | None = None,
) -> Estimate:
    """The typed estimate of docs/contract.md, from an identification: the one place it is assembled.

    ``static_moment_kgm`` is the grouped, identifiable static moment ``beta_j``; ``first_moment_kgm`` is the
    segment's own ``m_j l_j``, which like ``mass_kg`` and ``com_m`` needs the anthropometric prior.

    Parameters
    ----------
    result : the identification (a batch fit, a live window's, the recursive filter's).
    lengths_m : (n,) the segment lengths it used, m.
    posterior : masses and COMs fused with the prior, None if the fusion could not run.
    subject : the subject facts used for the prior.
    lengths_std_m : (n,) the lengths' standard errors, m (None: none known, as the recursive filter's).
    placement_sd_m : how far (1 sd per axis, m) a skin marker may sit from its joint centre, one value or
        (n + 1,) per chain point (:func:`bsp_ros.core.identification.placement.chain_placement_sd_m`): a segment
        length is the distance of two points, so its std holds both.
    contact_from_robot : the contact point came from the robot's handle pose, not the hand's skin marker.
    removed_samples : implausible samples removed before the fit, by kind (the fit adds those it removed).
    session : the ``session`` block (times, source, configuration); None or empty: none.

    Returns
    -------
    Estimate
        Frozen; ``to_json()`` is the document (strict JSON: no NaN).
    """
    n = lengths_m.size
    lengths_std = np.zeros(n) if lengths_std_m is None else lengths_std_m
    # Two markers' offsets along the segment move the measured length; the truth is the joint centres' distance.
    sd_m = np.broadcast_to(np.asarray(placement_sd_m, dtype=np.float64), (n + 1,))
    lengths_std = np.hypot(lengths_std, np.hypot(sd_m[:-1], sd_m[1:]))
    correlation = _correlation(result.covariance)
    return Estimate(
        method=result.method,
        segments=_segments(result, lengths_m, lengths_std, posterior),
        joints=_joints(result),
        passive_curves=_passive_curves(result),
        quality=_quality(result, posterior, contact_from_robot, removed_samples or {}),
        subject={"body_mass_kg": subject.body_mass_kg, "height_m": subject.height_m, "sex": subject.sex},
        diagnostics={
            "parameters": [f"{key}/{owner}" for key, owner in result.names],
            "correlation": [[_finite(c) for c in row] for row in correlation],
            **{k: v for k, v in result.diagnostics.items() if k not in ("paper_pi", "passive_curves")},
            **({"paper_pi": result.diagnostics["paper_pi"]} if "paper_pi" in result.diagnostics else {}),
        },
        software={"name": "bsp_ros", "version": __version__},
        session=dict(session) if session else None,
        extra=_speed_dependence(result),
    )


def _speed_dependence(result: IdentificationResult) -> dict[str, Any]:
    """The ``speed_dependence`` block of a session at two speeds (empty otherwise: no key)."""
    block = speed_dependence_block(result.findings)
    return {"speed_dependence": block} if block else {}


def estimate_from_fit(
    result: IdentificationResult,
    data: IdentificationData,
    *,
    posterior: Posterior | None,
    subject: SubjectInfo,
    placement_sd_m: float | np.ndarray = 0.0,
    session: Mapping[str, Any] | None = None,
) -> Estimate:
    """:func:`estimate_from_result` of a fit of ``data``: its segment lengths and their std, its contact point and
    the samples removed before the fit."""
    return estimate_from_result(
        result,
        lengths_m=data.lengths_m,
        lengths_std_m=data.lengths_std_m,
        posterior=posterior,
        subject=subject,
        placement_sd_m=placement_sd_m,
        contact_from_robot=data.contact_from_robot,
        removed_samples=data.removed_samples,
        session=session,
    )


def estimate_document(
    result: IdentificationResult,
    data: IdentificationData,
    posterior: Posterior | None,
    subject: SubjectInfo,
    session: dict[str, Any] | None = None,
    marker_placement_sd_m: float | np.ndarray = 0.0,
) -> dict[str, Any]:
    """The JSON of :func:`estimate_from_fit`, for callers that write the document at once (benches)."""
    fit = estimate_from_fit(
        result, data, posterior=posterior, subject=subject, placement_sd_m=marker_placement_sd_m, session=session
    )
    return fit.to_json()


def identified(result: IdentificationResult, i: int, source: str = "data") -> Quantity:
    """Parameter ``i`` of ``result`` as a quantity, with its uncertainty budget (``budget``: each ledger term's
    standard uncertainty, whose squares sum to the std's) where the result keeps a ledger."""
    out = quantity(result.values[i], result.std[i], source)
    budget = result.budget(i)
    if budget and out.std is not None:
        terms = {term: float(u) if math.isfinite(u) else None for term, u in budget.items()}
        return Quantity(value=out.value, std=out.std, source=out.source, budget=terms)
    return out


def _segments(
    result: IdentificationResult, lengths_m: np.ndarray, lengths_std_m: np.ndarray, posterior: Posterior | None
) -> dict[str, dict[str, Quantity]]:
    """The ``segments`` block: length, static moment, the fused masses and COMs, the base quantities."""
    n = lengths_m.size
    segments: dict[str, dict[str, Quantity]] = {}
    for j, segment in enumerate(segments_for(n)):
        entry = {
            "length_m": quantity(lengths_m[j], lengths_std_m[j], "data"),
            "static_moment_kgm": identified(result, result.index("static_moment_kgm", segment)),
        }
        if posterior is not None:
            cov = posterior.covariance
            entry["mass_kg"] = quantity(posterior.mean[j], math.sqrt(cov[j, j]), posterior.source(j))
            entry["com_m"] = quantity(posterior.mean[n + j], math.sqrt(cov[n + j, n + j]), posterior.source(n + j))
            entry["first_moment_kgm"] = quantity(
                posterior.first_moments_kgm[j], posterior.first_moments_std_kgm[j], posterior.first_moment_source(j)
            )
        else:
            for key in ("mass_kg", "com_m", "first_moment_kgm"):
                entry[key] = quantity(float("nan"), float("nan"), "prior")
        entry.update(base_quantities(result, posterior, lengths_m, j, segment))
        segments[segment] = entry
    return segments


def _joints(result: IdentificationResult) -> dict[str, dict[str, Quantity]]:
    """The ``joints`` block: each passive parameter."""
    joints: dict[str, dict[str, Quantity]] = {joint: {} for joint in joints_for(result.n_joints)}
    for i, (key, owner) in enumerate(result.names):
        if owner in joints:
            joints[owner][key] = identified(result, i)
    return joints


def _passive_curves(result: IdentificationResult) -> dict[str, Any]:
    """The passive curves of a valid estimate, by joint: the elastic passive moment over the measured range, what a
    clinician compares day to day."""
    curves: dict[str, Any] = result.diagnostics.get("passive_curves") or {}  # type: ignore[assignment]
    return {joint: curves[joint] for joint in joints_for(result.n_joints) if joint in curves and result.valid}


def _quality(
    result: IdentificationResult,
    posterior: Posterior | None,
    contact_from_robot: bool,
    removed: Mapping[str, int],
) -> Quality:
    """The ``quality`` block: the verdict, its findings, and what the std holds."""
    notes = list(posterior.notes) if posterior else []
    extra: dict[str, Any] = {
        "removed_samples": removed_samples(result, removed),
        # Where the handle wrench's point of action came from: it sets the lever arms (and their placement std).
        "contact_point": CONTACT_FROM_ROBOT if contact_from_robot else CONTACT_FROM_MARKER,
    }
    placement = result.diagnostics.get("marker_placement")
    # The skin markers' placement the std holds: as assumed, or wider where the data put them further off.
    marker_placement = PlacementBlock.from_json(placement) if isinstance(placement, Mapping) and placement else None
    key_order = ["removed_samples", "contact_point", *(["marker_placement"] if marker_placement else [])]
    sensitivity = result.diagnostics.get("offset_sensitivity_kgm_per_0_05_nm")
    if sensitivity:
        # What the data cannot test at one operating point, and what it would cost if false.
        extra["assumptions"] = [
            {
                "assumption": "no elastic passive offset at any joint (a constant passive moment is confounded "
                "with gravity over a small range of motion)",
                "static_moment_shift_kgm_per_0_05_nm": sensitivity,
            }
        ]
        key_order.append("assumptions")
    return Quality(
        valid=bool(result.valid),
        level=Level.INVALID if not result.valid else (Level.WEAK if result.weak else Level.OK),
        message=result.message,
        findings=(*result.findings, *(note(FindingCode.PRIOR_NOTE, t) for t in notes)),
        warnings=(*result.warnings, *notes),
        n_samples=int(result.n_samples),
        condition_number=float(result.condition_number) if math.isfinite(result.condition_number) else None,
        residual_rms_nm={k: float(v) for k, v in result.residual_rms_nm.items()},
        marker_placement=marker_placement,
        extra=extra,
        key_order=tuple(key_order),
    )


def source_from_prior_share(share: float | None) -> str:
    """``data``, ``data+prior`` or ``prior`` from posterior / prior variance (None: no prior, data alone)."""
    if share is None or not math.isfinite(share) or share < 0.05:
        return "data"
    return "prior" if share > 0.9 else "data+prior"


def base_quantities(
    result: IdentificationResult, posterior: Posterior | None, lengths_m: np.ndarray, j: int, segment: str
) -> dict[str, Quantity]:
    """The perpendicular moment and the inertias of segment ``j`` (empty when the model had no dynamics).

    ``grouped_inertia_kgm2`` is the identifiable base parameter (about the proximal joint, the distal masses
    lumped at the distal joint); ``inertia_kgm2`` (the segment alone, about its proximal joint) and
    ``inertia_com_kgm2`` (about its COM) subtract what the fused masses and COMs account for.
    """
    shares = result.diagnostics.get("prior_share", {})
    shares = shares if isinstance(shares, dict) else {}
    out: dict[str, Quantity] = {}
    for key in ("perpendicular_moment_kgm", "grouped_inertia_kgm2"):
        if (key, segment) in result.names:
            i = result.index(key, segment)
            out[key] = identified(result, i, source_from_prior_share(shares.get(f"{key}/{segment}")))
    if "grouped_inertia_kgm2" not in out or posterior is None:
        return out
    n = lengths_m.size
    zeta = out["grouped_inertia_kgm2"]
    distal = list(range(j + 1, n))
    masses, cov = posterior.mean, posterior.covariance
    distal_mass = float(masses[distal].sum()) if distal else 0.0
    distal_var = float(cov[np.ix_(distal, distal)].sum()) if distal else 0.0
    a2 = float(lengths_m[j]) ** 2
    own = zeta.value - a2 * distal_mass if zeta.value is not None else float("nan")
    own_std = math.sqrt((zeta.std or 0.0) ** 2 + a2**2 * distal_var)
    source = zeta.source if not distal else (Source.PRIOR if zeta.source is Source.PRIOR else Source.DATA_PRIOR)
    out["inertia_kgm2"] = quantity(own, own_std, source)
    m, com = float(masses[j]), float(masses[n + j])
    about_com = own - m * com**2
    # m l^2 from the fused mass and COM (their covariance by first-order propagation).
    gradient = np.zeros(2 * n)
    gradient[j], gradient[n + j] = com**2, 2 * m * com
    com_var = float(gradient @ cov @ gradient)
    out["inertia_com_kgm2"] = quantity(
        about_com, math.sqrt(own_std**2 + com_var), "prior" if source is Source.PRIOR else "data+prior"
    )
    return out


def removed_samples(result: IdentificationResult, removed: Mapping[str, int]) -> dict[str, int]:
    """Implausible samples removed before (``removed``) or during the fit, by kind (``wrench_spikes``,
    ``marker_elbow``...)."""
    found = result.diagnostics.get("removed_samples", {})
    merged = dict(removed)
    if isinstance(found, dict):
        merged.update({str(k): int(v) for k, v in found.items()})
    return merged


def _clean(number: float) -> float | None:
    return float(number) if math.isfinite(number) else None


def _finite(number: float) -> float | None:
    return round(float(number), 6) if math.isfinite(number) else None


def _correlation(covariance: np.ndarray) -> np.ndarray:
    std = np.sqrt(np.clip(np.diag(covariance), 0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(covariance / np.outer(std, std))
