"""Arm weight support: the hand wrench that carries a fraction of the identified gravity torques."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from bsp_ros.core.estimate_schema import Estimate
from bsp_ros.core.model import check_lengths_m, contact_jacobian, gravity_regressor
from bsp_ros.errors import InputError
from bsp_ros.validation import check_finite_array, check_finite_scalar

MIN_ELBOW_SIN = math.sin(math.radians(5.0))
"""Below this ``|sin q2|`` (elbow within 5 deg of straight or folded) the hand force cannot carry the arm."""


class SingularPoseError(InputError):
    """The arm is (nearly) straight or folded: ``J(q)^T`` is singular, no finite support wrench exists."""


@dataclass(frozen=True)
class SupportWrench:
    """The wrench the robot applies to the hand, in ``world`` at the contact point.

    Attributes
    ----------
    wrench_yzx : (3,) ``[F_y (N), F_z (N), M_x (Nm)]``; ``M_x`` is 0 for a 2-segment chain.
    covariance : (3, 3) its covariance from the static moments' covariance (N, N, Nm units squared).
    support_fraction : the fraction ``s`` of the gravity torques carried.
    elbow_sin : ``|sin q2|``, how far the pose is from the straight-arm singularity (1 = right angle).
    """

    wrench_yzx: np.ndarray
    covariance: np.ndarray
    support_fraction: float
    elbow_sin: float

    @property
    def std(self) -> np.ndarray:
        """(3,) one standard deviation of each component."""
        return np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))


def support_matrix(q_rad: npt.ArrayLike, lengths_m: npt.ArrayLike, support_fraction: float) -> np.ndarray:
    """The linear map ``A`` with ``F_support = A @ beta``.

    Parameters
    ----------
    q_rad : (n,) joint angles (rad), n = 2 or 3.
    lengths_m : (n,) segment lengths (m).
    support_fraction : ``s`` in [0, 1].

    Returns
    -------
    (3, n) ``A = s (J_c^T)^{-1} Y(q)``, where ``J_c`` holds the Jacobian rows the chain can transmit
    (F_y, F_z, M_x for 3 segments; F_y, F_z for 2, whose row of ``A`` for M_x is zero).

    Raises
    ------
    SingularPoseError
        If the elbow is within 5 deg of straight or folded (``|sin q2| < sin 5 deg``).
    InputError
        On non-finite angles, a fraction outside [0, 1], or mismatched sizes.
    """
    lengths = check_lengths_m(lengths_m)
    n = lengths.size
    q = check_finite_array("joint angles (rad)", q_rad, (n,))
    s = check_finite_scalar("support_fraction", support_fraction, 0.0, 1.0)
    elbow_sin = abs(math.sin(float(q[1])))
    if elbow_sin < MIN_ELBOW_SIN:
        raise SingularPoseError(
            f"elbow angle {math.degrees(float(q[1])):.1f} deg is within 5 deg of a straight or folded arm: "
            "J(q)^T is singular there, so no hand wrench can carry the arm's weight; no support computed"
        )
    jacobian = contact_jacobian(q[None, :], lengths)[0]  # (3, n)
    rows = 3 if n == 3 else 2  # a 2-segment chain holds a bearing: it transmits no moment
    regressor = gravity_regressor(q[None, :])[0]  # (n, n)
    matrix = np.zeros((3, n))
    matrix[:rows] = s * np.linalg.solve(jacobian[:rows].T, regressor)
    return matrix


def support_wrench(
    q_rad: npt.ArrayLike,
    lengths_m: npt.ArrayLike,
    static_moments_kgm: npt.ArrayLike,
    support_fraction: float,
    static_moments_covariance: npt.ArrayLike | None = None,
) -> SupportWrench:
    """The hand wrench with ``J(q)^T F_support = s tau_G(q)`` (docs/contract.md "Weight support").

    Parameters
    ----------
    q_rad : (n,) joint angles (rad), docs/contract.md conventions, n = 2 or 3.
    lengths_m : (n,) segment lengths (m).
    static_moments_kgm : (n,) grouped static moments ``beta`` (kg m).
    support_fraction : ``s`` in [0, 1] of the gravity torques to carry.
    static_moments_covariance : (n, n) covariance of ``beta`` (kg^2 m^2); None means exact.

    Returns
    -------
    SupportWrench
        ``[F_y, F_z, M_x]`` in ``world`` at the contact point and its covariance ``A Sigma A^T``
        (the wrench is linear in ``beta``; angles and lengths are taken as exact).

    Raises
    ------
    SingularPoseError
        Near the straight/folded arm.
    InputError
        On non-finite or mis-shaped input, or a covariance that is not symmetric positive semi-definite.
    """
    lengths = check_lengths_m(lengths_m)
    n = lengths.size
    beta = check_finite_array("static moments (kg m)", static_moments_kgm, (n,))
    matrix = support_matrix(q_rad, lengths, support_fraction)
    if static_moments_covariance is None:
        covariance_beta = np.zeros((n, n))
    else:
        covariance_beta = check_finite_array("static moment covariance", static_moments_covariance, (n, n))
        if not np.allclose(covariance_beta, covariance_beta.T, rtol=1e-9, atol=1e-15):
            raise InputError("static moment covariance must be symmetric")
        if (np.diag(covariance_beta) < 0).any():
            raise InputError(f"static moment covariance has negative variances {np.diag(covariance_beta).tolist()}")
    wrench = matrix @ beta
    covariance = matrix @ covariance_beta @ matrix.T
    return SupportWrench(
        wrench,
        0.5 * (covariance + covariance.T),
        float(support_fraction),
        abs(math.sin(float(np.asarray(q_rad, dtype=float)[1]))),
    )


@dataclass(frozen=True)
class SupportDecision:
    """What the live node publishes: a wrench, or None with the reason it publishes nothing."""

    wrench: SupportWrench | None
    reason: str

    def diagnostics(self) -> dict[str, str]:
        """Key-values for a ``/diagnostics`` status: the wrench, its one-std uncertainty and the reason."""
        values = {"reason": self.reason}
        if self.wrench is not None:
            values["support_fraction"] = f"{self.wrench.support_fraction:g}"
            values["elbow_sin"] = f"{self.wrench.elbow_sin:.3f}"
            for name, value, std in zip(
                ("F_y_N", "F_z_N", "M_x_Nm"), self.wrench.wrench_yzx, self.wrench.std, strict=True
            ):
                values[name] = f"{value:.4g}"
                values[f"{name}_std"] = f"{std:.2g}"
        return values


def estimate_from_result(result: Any) -> dict[str, Any]:
    """The ``estimate`` argument of :func:`live_support` from an ``IdentificationResult``."""
    _, values, covariance = result.block("static_moment_kgm")
    return {"valid": bool(result.valid), "static_moments_kgm": values, "covariance": covariance}


def support_inputs(estimate: Estimate) -> dict[str, Any] | None:
    """The ``estimate`` argument of :func:`live_support` from an :class:`Estimate`.

    The static moments' covariance is rebuilt from their std and the estimate's ``diagnostics.correlation``
    (over ``diagnostics.parameters``); without those, their std alone (no correlation). None when the
    estimate holds no static moments.
    """
    names = [s for s in ("upper_arm", "forearm", "hand") if s in estimate.segments]
    moments = [estimate.quantity("static_moment_kgm", s) for s in names]
    if not names or not all(q is not None and q.finite for q in moments):
        return None
    values = np.array([q.value for q in moments if q is not None], dtype=np.float64)
    std = np.array([q.std for q in moments if q is not None], dtype=np.float64)
    correlation = np.eye(len(names))
    diagnostics = estimate.diagnostics or {}
    order = list(diagnostics.get("parameters") or [])
    matrix = diagnostics.get("correlation")
    picks = [order.index(f"static_moment_kgm/{s}") if f"static_moment_kgm/{s}" in order else -1 for s in names]
    if matrix is not None and min(picks) >= 0:
        block = np.array([[matrix[i][j] for j in picks] for i in picks], dtype=np.float64)
        if np.isfinite(block).all():
            correlation = block
    return {"valid": estimate.valid, "static_moments_kgm": values, "covariance": correlation * np.outer(std, std)}


def live_support(
    estimate: Mapping[str, Any] | None,
    q_rad: npt.ArrayLike | None,
    lengths_m: npt.ArrayLike | None,
    support_fraction: float,
) -> SupportDecision:
    """The support wrench for the latest estimate and joint state, or None with why (never raises).

    Parameters
    ----------
    estimate : the latest estimate as ``{"valid": bool, "static_moments_kgm": (n,), "covariance": (n, n)}``
        (covariance of the static moments, optional), or None before the first estimate.
    q_rad : (n,) the latest joint angles (rad), or None if none yet.
    lengths_m : (n,) segment lengths (m), or None if unknown yet.
    support_fraction : ``s`` in [0, 1] (node parameter ``support_fraction``).

    Returns
    -------
    SupportDecision
        ``wrench`` None while there is no valid estimate, no joint state, or the pose is singular;
        ``reason`` says which, for ``/diagnostics``.
    """
    if estimate is None:
        return SupportDecision(None, "no estimate yet: no support published")
    if estimate.get("valid") is not True:
        return SupportDecision(None, "the latest estimate is not valid: no support published")
    if q_rad is None or lengths_m is None:
        return SupportDecision(None, "no joint state yet: no support published")
    try:
        wrench = support_wrench(
            q_rad, lengths_m, estimate["static_moments_kgm"], support_fraction, estimate.get("covariance")
        )
    except SingularPoseError as error:
        return SupportDecision(None, str(error))
    except (InputError, KeyError) as error:
        return SupportDecision(None, f"cannot compute support: {error}")
    return SupportDecision(wrench, f"support {support_fraction:g} of the arm's gravity torques")
