"""Elastic passive moments beyond a linear spring: nonlinear in a joint's own angle, coupled between adjacent
joints (two-joint muscles), both as gradients of a polynomial elastic potential so that the fit stays linear."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from bsp_ros.core.identification.result import ParameterName
from bsp_ros.core.streams import joints_for

# Parameter keys (docs/contract.md, joints.<joint>): the x^2 and x^3 moments at the edge of the measured range
# (x = (q - centre) / half range, so the value is the moment the term adds there, Nm), and the stiffness shared
# with the proximal joint, d tau_j / d q_{j-1} = d tau_{j-1} / d q_j (Nm/rad; a conservative elastic field has
# a symmetric stiffness, which is what two-joint muscles crossing both joints give).
QUADRATIC_KEY = "elastic_quadratic_nm"
CUBIC_KEY = "elastic_cubic_nm"
# The elastic potential's next order (``higher``, the shape probe of a nonlinear model, selection.shape_probe):
# per joint an x^4 moment, per adjacent pair the gradients of x_a^3 x_b, x_a^2 x_b^2 and x_a x_b^3 (Nm at the
# range edges, in the distal joint's row for the first two, the proximal's for the last).
QUARTIC_KEY = "elastic_quartic_nm"
COUPLING_HIGHER_KEYS = ("coupling_31_nm", "coupling_22_nm", "coupling_13_nm")
COUPLING_KEY = "coupling_nm_per_rad"
# With both terms, the two-joint moments also bend: potential terms x_{j-1}^2 x_j and x_{j-1} x_j^2, keyed by the
# moment they add in joint j's row (resp. joint j-1's) at the range edges (Nm).
COUPLING_PROXIMAL_KEY = "coupling_proximal_nm"
COUPLING_DISTAL_KEY = "coupling_distal_nm"
# Zero-mean Gaussian priors of the terms beyond a linear spring (1 sd, in each key's unit). Over one posture a
# polynomial in a joint's angle can mimic its gravity torque (a cubic matches cos q over 0.2 rad to 4e-6), so
# without a scale these terms would trade against the static moments on the smallest misfit; the prior keeps
# that trade in the std. Scale: relaxed arms show passive moments of a few tenths of a Nm to about 1 Nm over
# a mid range and stiffen towards its ends (Riener and Edrich 1999; Amankwah et al. 2004).
ELASTIC_PRIOR_SD = {
    QUADRATIC_KEY: 1.0,
    CUBIC_KEY: 1.0,
    QUARTIC_KEY: 1.0,
    **dict.fromkeys(COUPLING_HIGHER_KEYS, 1.0),
    COUPLING_KEY: 2.0,
    COUPLING_PROXIMAL_KEY: 1.0,
    COUPLING_DISTAL_KEY: 1.0,
}


def elastic_prior_precision(names: list[ParameterName]) -> np.ndarray:
    """(p,) the Gaussian prior precisions 1 / sd^2 of the elastic terms among ``names`` (0 for every other one)."""
    return np.array([1.0 / ELASTIC_PRIOR_SD[key] ** 2 if key in ELASTIC_PRIOR_SD else 0.0 for key, _ in names])


# A range narrower than this (rad) is not scaled up: its nonlinear columns would be noise amplifiers.
MIN_HALF_RANGE_RAD = 0.01


@dataclass(frozen=True)
class ElasticReference:
    """Where the elastic polynomial is centred and scaled: per joint, the measured range's centre and half width
    (rad, shapes (n,)), and the session's mean angles (rad, (n,)) at which curves hold the other joints."""

    centre_rad: np.ndarray
    half_range_rad: np.ndarray
    mean_rad: np.ndarray

    @classmethod
    def from_angles(cls, q_rad: np.ndarray) -> ElasticReference:
        """The reference of angles ``q_rad`` (N, n): range between the 0.5th and 99.5th percentiles."""
        low, high = np.percentile(q_rad, [0.5, 99.5], axis=0)
        half = np.maximum(0.5 * (high - low), MIN_HALF_RANGE_RAD)
        return cls(0.5 * (low + high), half, q_rad.mean(axis=0))

    def to_dict(self) -> dict[str, list[float]]:
        """JSON form, degrees (``diagnostics.elastic_reference``)."""
        return {
            "centre_deg": np.degrees(self.centre_rad).tolist(),
            "half_range_deg": np.degrees(self.half_range_rad).tolist(),
            "mean_deg": np.degrees(self.mean_rad).tolist(),
        }


def elastic_names(terms: tuple[str, ...], n: int) -> list[ParameterName]:
    """Parameter names of the elastic ``terms`` (``nonlinear``, ``coupling``) of an ``n``-joint chain."""
    joints = joints_for(n)
    names: list[ParameterName] = []
    if "nonlinear" in terms:
        for joint in joints:
            names += [(QUADRATIC_KEY, joint), (CUBIC_KEY, joint)]
    if "coupling" in terms:
        names += [(COUPLING_KEY, joint) for joint in joints[1:]]
    if "coupling" in terms and "nonlinear" in terms:
        for joint in joints[1:]:
            names += [(COUPLING_PROXIMAL_KEY, joint), (COUPLING_DISTAL_KEY, joint)]
    if "higher" in terms:
        names += [(QUARTIC_KEY, joint) for joint in joints]
        if "coupling" in terms:
            names += [(key, joint) for joint in joints[1:] for key in COUPLING_HIGHER_KEYS]
    return names


def elastic_columns(q_rad: np.ndarray, terms: tuple[str, ...], reference: ElasticReference) -> np.ndarray:
    """Regressor columns (N, n, m) of the elastic ``terms``, in the order of :func:`elastic_names`.

    Parameters
    ----------
    q_rad : (N, n) joint angles, rad.
    terms : out of ``nonlinear`` (per joint: ``x^2``, ``x^3`` in its own row), ``coupling`` (per adjacent
        pair: ``q_j - c_j`` in row ``j - 1`` and ``q_{j-1} - c_{j-1}`` in row ``j``) and ``higher`` (per joint:
        ``x^4`` in its own row; with ``coupling``, per adjacent pair the gradients of the potentials
        ``x_a^3 x_b``, ``x_a^2 x_b^2``, ``x_a x_b^3``).
    reference : centres and half ranges of the normalised angles ``x``.
    """
    n = q_rad.shape[1]
    deviation = q_rad - reference.centre_rad[None, :]
    x = deviation / reference.half_range_rad[None, :]
    blocks = []
    if "nonlinear" in terms:
        block = np.zeros((q_rad.shape[0], n, 2 * n))
        for j in range(n):
            block[:, j, 2 * j] = x[:, j] ** 2
            block[:, j, 2 * j + 1] = x[:, j] ** 3
        blocks.append(block)
    if "coupling" in terms:
        block = np.zeros((q_rad.shape[0], n, n - 1))
        for j in range(1, n):
            block[:, j - 1, j - 1] = deviation[:, j]
            block[:, j, j - 1] = deviation[:, j - 1]
        blocks.append(block)
    if "coupling" in terms and "nonlinear" in terms:
        # Gradients of u x_a^2 x_b and v x_a x_b^2 (a = j - 1, b = j), scaled so u, v are edge moments (Nm).
        h = reference.half_range_rad
        block = np.zeros((q_rad.shape[0], n, 2 * (n - 1)))
        for j in range(1, n):
            a, b = j - 1, j
            block[:, b, 2 * a] = x[:, a] ** 2
            block[:, a, 2 * a] = 2.0 * x[:, a] * x[:, b] * h[b] / h[a]
            block[:, a, 2 * a + 1] = x[:, b] ** 2
            block[:, b, 2 * a + 1] = 2.0 * x[:, a] * x[:, b] * h[a] / h[b]
        blocks.append(block)
    if "higher" in terms:
        block = np.zeros((q_rad.shape[0], n, n))
        for j in range(n):
            block[:, j, j] = x[:, j] ** 4
        blocks.append(block)
    if "higher" in terms and "coupling" in terms:
        h = reference.half_range_rad
        block = np.zeros((q_rad.shape[0], n, 3 * (n - 1)))
        for j in range(1, n):
            a, b, c = j - 1, j, 3 * (j - 1)
            xa, xb = x[:, a], x[:, b]
            block[:, b, c], block[:, a, c] = xa**3, 3.0 * xa**2 * xb * h[b] / h[a]  # x_a^3 x_b
            block[:, b, c + 1], block[:, a, c + 1] = xa**2 * xb, xa * xb**2 * h[b] / h[a]  # x_a^2 x_b^2 / 2
            block[:, a, c + 2], block[:, b, c + 2] = xb**3, 3.0 * xa * xb**2 * h[a] / h[b]  # x_a x_b^3
        blocks.append(block)
    if not blocks:
        return np.zeros((q_rad.shape[0], n, 0))
    return np.concatenate(blocks, axis=2)


# Points of a reported passive curve over the measured range.
CURVE_POINTS = 9


def curve_angles_rad(reference: ElasticReference, points: int = CURVE_POINTS) -> np.ndarray:
    """(n, points) angles over each joint's measured range, rad."""
    steps = np.linspace(-1.0, 1.0, points)
    return np.asarray(reference.centre_rad[:, None] + reference.half_range_rad[:, None] * steps[None, :])


def curve_gradients(
    names: list[ParameterName], terms: tuple[str, ...], reference: ElasticReference, points: int = CURVE_POINTS
) -> np.ndarray:
    """(n, points + 1, p): per joint, the elastic passive moment at :func:`curve_angles_rad` (the other joints at
    their session means) and, last, its slope d tau / d q at the joint's mean angle, as linear maps of the
    parameters ``names`` (Nm and Nm/rad per unit of each parameter); ``terms`` are the model's elastic terms.
    Friction terms do not enter."""
    n = reference.centre_rad.size
    joints = joints_for(n)
    angles = curve_angles_rad(reference, points)
    step = 1e-4  # rad, central difference of the slope
    index = {name: i for i, name in enumerate(names)}
    extra = elastic_names(terms, n)
    out = np.zeros((n, points + 1, len(names)))
    for j, joint in enumerate(joints):
        q = np.repeat(reference.mean_rad[None, :], points + 2, axis=0)
        q[:points, j] = angles[j]
        q[points:, j] = reference.mean_rad[j] + np.array([-step, step])
        rows = np.zeros((points + 2, len(names)))
        if ("offset_nm", joint) in index:
            rows[:, index[("offset_nm", joint)]] = 1.0
        if ("stiffness_nm_per_rad", joint) in index:
            rows[:, index[("stiffness_nm_per_rad", joint)]] = q[:, j]
        columns = elastic_columns(q, terms, reference)[:, j, :]
        for c, name in enumerate(extra):
            if name in index:
                rows[:, index[name]] += columns[:, c]
        out[j, :points] = rows[:points]
        out[j, points] = (rows[points + 1] - rows[points]) / (2.0 * step)
    return out


def curve_variance(gradients: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """(n, K + 1) variances of the points and slopes of :func:`curve_gradients` (n, K + 1, p) under ``covariance``."""
    return np.clip(np.einsum("jkp,pq,jkq->jk", gradients, covariance, gradients), 0.0, None)


def passive_curves(
    gradients: np.ndarray,
    values: np.ndarray,
    covariance: np.ndarray,
    reference: ElasticReference,
    extra_variance: np.ndarray | None = None,
) -> dict[str, dict[str, Any]]:
    """Joint -> ``{"angle_deg", "moment_nm", "std_nm", "reference_angle_deg", "stiffness_nm_per_rad",
    "stiffness_std_nm_per_rad"}`` from :func:`curve_gradients` (n, K + 1, p) and the estimate (p,), (p, p);
    ``extra_variance`` (n, K + 1) joins the variance of each point and slope (what a model choice leaves open)."""
    n, k_points = gradients.shape[0], gradients.shape[1] - 1
    angles = curve_angles_rad(reference, k_points)
    variance = curve_variance(gradients, covariance)
    if extra_variance is not None:
        variance = variance + extra_variance
    out: dict[str, dict[str, Any]] = {}
    for j, joint in enumerate(joints_for(n)):
        mean = gradients[j] @ values
        std = np.sqrt(variance[j])
        out[joint] = {
            "angle_deg": np.degrees(angles[j]).tolist(),
            "moment_nm": mean[:k_points].tolist(),
            "std_nm": std[:k_points].tolist(),
            "reference_angle_deg": float(np.degrees(reference.mean_rad[j])),
            "stiffness_nm_per_rad": float(mean[k_points]),
            "stiffness_std_nm_per_rad": float(std[k_points]),
        }
    return out
