"""The `bsp_ros/core/estimate/1` document of docs/contract.md, built from an identification and a fused prior."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from bsp_ros import __version__
from bsp_ros.core.contact_point import CONTACT_FROM_MARKER, CONTACT_FROM_ROBOT
from bsp_ros.core.estimate_schema import SCHEMA
from bsp_ros.core.findings import Finding, FindingCode, Severity, note
from bsp_ros.core.fusion import Posterior, SubjectInfo
from bsp_ros.core.identification.data import IdentificationData
from bsp_ros.core.identification.result import IdentificationResult
from bsp_ros.core.quantities import PASSIVE_CURVE
from bsp_ros.core.streams import joints_for, segments_for


def quantity(value: float, std: float, source: str) -> dict[str, Any]:
    """One docs/contract.md quantity; a value that could not be computed is ``null``, never NaN."""

    def clean(number: float) -> float | None:
        return float(number) if math.isfinite(number) else None

    return {"value": clean(value), "std": clean(std), "source": source}


def invalid_document(method: str, finding: Finding) -> dict[str, Any]:
    """An estimate document with no parameters, made invalid by ``finding`` (live inputs not usable)."""
    return {
        "schema": SCHEMA,
        "method": method,
        "segments": {},
        "joints": {},
        "quality": {
            "valid": False,
            "n_samples": 0,
            "condition_number": None,
            "residual_rms_nm": {},
            "warnings": [],
            "message": finding.text,
            "findings": [finding.to_json()],
            "level": "invalid",
        },
    }


def add_finding(quality: dict[str, Any], finding: Finding, at: int | None = None) -> None:
    """Add ``finding`` to an estimate document's ``quality`` block, in place: to ``findings``, and its text to the
    ``message`` (an invalid one, first) or to the ``warnings`` (at index ``at``, else last)."""
    findings = quality.setdefault("findings", [])
    if finding.severity is Severity.INVALID:
        # The likeliest cause of what else the estimate found (a lost transform makes the model misfit): first.
        findings.insert(0, finding.to_json())
        quality["message"] = finding.text + (f"; {quality['message']}" if not quality["valid"] else "")
        quality["valid"], quality["level"] = False, "invalid"
        return
    findings.append(finding.to_json())
    warnings = quality.setdefault("warnings", [])
    warnings.insert(len(warnings) if at is None else at, finding.text)


def estimate_document(
    result: IdentificationResult,
    data: IdentificationData,
    posterior: Posterior | None,
    subject: SubjectInfo,
    session: dict[str, Any] | None = None,
    marker_placement_sd_m: float | np.ndarray = 0.0,
) -> dict[str, Any]:
    """Build the estimate JSON (as a dict) of docs/contract.md.

    ``static_moment_kgm`` is the grouped, identifiable static moment ``beta_j``; ``first_moment_kgm`` is the
    segment's own ``m_j l_j``, which like ``mass_kg`` and ``com_m`` needs the anthropometric prior.

    Parameters
    ----------
    result : the identification.
    data : what it was identified from (segment lengths).
    posterior : masses and COMs fused with the prior, None if the fusion could not run.
    subject : the subject facts used for the prior.
    session : extra facts about the session (times, source, configuration).
    marker_placement_sd_m : how far (1 sd per axis, m) a skin marker may sit from its joint centre, one value or
        (n + 1,) per chain point (:func:`chain_placement_sd_m`): a segment length is the distance of two points,
        so its std holds both.

    Returns
    -------
    A JSON-ready dict (strict JSON: no NaN).
    """
    segments = _segments(result, data, posterior, marker_placement_sd_m)
    joints = _joints(result)
    correlation = _correlation(result.covariance)
    document: dict[str, Any] = {
        "schema": SCHEMA,
        "method": result.method,
        "segments": segments,
        "joints": joints,
        "quality": _quality(result, data, posterior),
        "subject": {"body_mass_kg": subject.body_mass_kg, "height_m": subject.height_m, "sex": subject.sex},
        "diagnostics": {
            "parameters": [f"{key}/{owner}" for key, owner in result.names],
            "correlation": [[_finite(c) for c in row] for row in correlation],
            **{k: v for k, v in result.diagnostics.items() if k not in ("paper_pi", "passive_curves")},
            **({"paper_pi": result.diagnostics["paper_pi"]} if "paper_pi" in result.diagnostics else {}),
        },
        "software": {"name": "bsp_ros", "version": __version__},
    }
    if session:
        document["session"] = session
    return document


def identified(result: IdentificationResult, i: int, source: str = "data") -> dict[str, Any]:
    """Parameter ``i`` of ``result`` as a docs/contract.md quantity, with its uncertainty budget (``budget``: each
    ledger term's standard uncertainty, whose squares sum to the std's) where the result keeps a ledger."""
    out = quantity(result.values[i], result.std[i], source)
    budget = result.budget(i)
    if budget and out["std"] is not None:
        out["budget"] = {term: float(u) if math.isfinite(u) else None for term, u in budget.items()}
    return out


def _segments(
    result: IdentificationResult,
    data: IdentificationData,
    posterior: Posterior | None,
    marker_placement_sd_m: float | np.ndarray,
) -> dict[str, dict[str, Any]]:
    """The ``segments`` block: length, static moment, the fused masses and COMs, the base quantities."""
    n = data.n_joints
    # Two markers' offsets along the segment move the measured length; the truth is the joint centres' distance.
    sd_m = np.broadcast_to(np.asarray(marker_placement_sd_m, dtype=np.float64), (n + 1,))
    lengths_std_m = np.hypot(data.lengths_std_m, np.hypot(sd_m[:-1], sd_m[1:]))
    segments: dict[str, dict[str, Any]] = {}
    for j, segment in enumerate(segments_for(n)):
        entry = {
            "length_m": quantity(data.lengths_m[j], lengths_std_m[j], "data"),
            "static_moment_kgm": identified(result, result.index("static_moment_kgm", segment)),
        }
        if posterior is not None:
            cov = posterior.covariance
            entry["mass_kg"] = quantity(posterior.mean[j], math.sqrt(cov[j, j]), posterior.source(j))
            entry["com_m"] = quantity(posterior.mean[n + j], math.sqrt(cov[n + j, n + j]), posterior.source(n + j))
            share = max(posterior.prior_share[j], posterior.prior_share[n + j])
            entry["first_moment_kgm"] = quantity(
                posterior.first_moments_kgm[j],
                posterior.first_moments_std_kgm[j],
                "prior" if share > 0.999 else "data+prior",
            )
        else:
            for key in ("mass_kg", "com_m", "first_moment_kgm"):
                entry[key] = quantity(float("nan"), float("nan"), "prior")
        entry.update(base_quantities(result, posterior, data.lengths_m, j, segment))
        segments[segment] = entry
    return segments


def _joints(result: IdentificationResult) -> dict[str, dict[str, Any]]:
    """The ``joints`` block: each passive parameter, and the passive curves of a valid estimate."""
    joints: dict[str, dict[str, Any]] = {joint: {} for joint in joints_for(result.n_joints)}
    for i, (key, owner) in enumerate(result.names):
        if owner in joints:
            joints[owner][key] = identified(result, i)
    curves: dict[str, Any] = result.diagnostics.get("passive_curves") or {}  # type: ignore[assignment]
    for joint, curve in curves.items():
        # The elastic passive moment over the measured range: what a clinician compares day to day.
        if joint in joints and result.valid:
            joints[joint][PASSIVE_CURVE] = curve
    return joints


def _quality(result: IdentificationResult, data: IdentificationData, posterior: Posterior | None) -> dict[str, Any]:
    """The ``quality`` block: the verdict, its findings, and what the std holds."""
    notes = list(posterior.notes) if posterior else []
    quality: dict[str, Any] = {
        "valid": bool(result.valid),
        "n_samples": int(result.n_samples),
        "condition_number": float(result.condition_number) if math.isfinite(result.condition_number) else None,
        "residual_rms_nm": {k: float(v) for k, v in result.residual_rms_nm.items()},
        "warnings": list(result.warnings) + notes,
        "message": result.message,
        "findings": [f.to_json() for f in result.findings] + [note(FindingCode.PRIOR_NOTE, t).to_json() for t in notes],
        "level": "invalid" if not result.valid else ("weak" if result.weak else "ok"),
        "removed_samples": removed_samples(result, data),
        # Where the handle wrench's point of action came from: it sets the lever arms (and their placement std).
        "contact_point": CONTACT_FROM_ROBOT if data.contact_from_robot else CONTACT_FROM_MARKER,
    }
    placement = result.diagnostics.get("marker_placement")
    if placement:
        # The skin markers' placement the std holds: as assumed, or wider where the data put them further off.
        quality["marker_placement"] = placement
    sensitivity = result.diagnostics.get("offset_sensitivity_kgm_per_0_05_nm")
    if sensitivity:
        # What the data cannot test at one operating point, and what it would cost if false.
        quality["assumptions"] = [
            {
                "assumption": "no elastic passive offset at any joint (a constant passive moment is confounded "
                "with gravity over a small range of motion)",
                "static_moment_shift_kgm_per_0_05_nm": sensitivity,
            }
        ]
    return quality


def source_from_prior_share(share: float | None) -> str:
    """``data``, ``data+prior`` or ``prior`` from posterior / prior variance (None: no prior, data alone)."""
    if share is None or not math.isfinite(share) or share < 0.05:
        return "data"
    return "prior" if share > 0.9 else "data+prior"


def base_quantities(
    result: IdentificationResult, posterior: Posterior | None, lengths_m: np.ndarray, j: int, segment: str
) -> dict[str, dict[str, Any]]:
    """The perpendicular moment and the inertias of segment ``j`` (empty when the model had no dynamics).

    ``grouped_inertia_kgm2`` is the identifiable base parameter (about the proximal joint, the distal masses
    lumped at the distal joint); ``inertia_kgm2`` (the segment alone, about its proximal joint) and
    ``inertia_com_kgm2`` (about its COM) subtract what the fused masses and COMs account for.
    """
    shares = result.diagnostics.get("prior_share", {})
    shares = shares if isinstance(shares, dict) else {}
    out: dict[str, dict[str, Any]] = {}
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
    own = zeta["value"] - a2 * distal_mass if zeta["value"] is not None else float("nan")
    own_std = math.sqrt((zeta["std"] or 0.0) ** 2 + a2**2 * distal_var)
    source = zeta["source"] if not distal else ("prior" if zeta["source"] == "prior" else "data+prior")
    out["inertia_kgm2"] = quantity(own, own_std, source)
    m, com = float(masses[j]), float(masses[n + j])
    about_com = own - m * com**2
    # m l^2 from the fused mass and COM (their covariance by first-order propagation).
    gradient = np.zeros(2 * n)
    gradient[j], gradient[n + j] = com**2, 2 * m * com
    com_var = float(gradient @ cov @ gradient)
    out["inertia_com_kgm2"] = quantity(
        about_com, math.sqrt(own_std**2 + com_var), "prior" if source == "prior" else "data+prior"
    )
    return out


def removed_samples(result: IdentificationResult, data: IdentificationData) -> dict[str, int]:
    """Implausible samples removed before or during the fit, by kind (``wrench_spikes``, ``marker_elbow``...)."""
    found = result.diagnostics.get("removed_samples", {})
    merged = dict(data.removed_samples)
    if isinstance(found, dict):
        merged.update({str(k): int(v) for k, v in found.items()})
    return merged


def _finite(number: float) -> float | None:
    return round(float(number), 6) if math.isfinite(number) else None


def _correlation(covariance: np.ndarray) -> np.ndarray:
    std = np.sqrt(np.clip(np.diag(covariance), 0, None))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(covariance / np.outer(std, std))
