"""The per-comparison level of a change that the next session confirms, so that a report's false flags stay rare.

A step between sessions ``i - 1`` and ``i`` beyond the level is a possible change; it is flagged when session
``i + 1``, compared with the same earlier session ``i - 1``, is beyond it too, in the same direction. Under no
change the two differences share the earlier session, so they are correlated 0.5, and the retest SD that scales
both is itself estimated from ``dof`` pairs. The level is chosen so that one confirmation happens by chance with
at most ``alpha / confirmations``: summed over the report's confirmations (Bonferroni), an unchanged arm is flagged
anywhere at most ``alpha`` of the time.
"""

from __future__ import annotations

import functools
import math

SHARED_VISIT_CORRELATION = 0.5
"""Correlation of two differences from one earlier session, of equal variance, under no change."""
SD_QUANTILES = 400
"""Quantiles of the retest SD's sampling distribution averaged over (deterministic quadrature)."""


def confirmation_chance(factor: float, dof: int) -> float:
    """The chance under no change that both differences of one confirmation exceed ``factor`` times the retest SD
    estimated from ``dof`` pairs, in the same direction.

    ``2 E_s[P(Z1 > factor s, Z2 > factor s)]``, ``(Z1, Z2)`` standard bivariate normal of correlation
    :data:`SHARED_VISIT_CORRELATION` (Owen's T: ``P = Q(h) - 2 T(h, sqrt((1 - rho) / (1 + rho)))``), ``s`` the
    estimated SD over the true, ``sqrt(chi2(dof) / dof)``, averaged over :data:`SD_QUANTILES` quantiles.
    """
    import numpy as np
    from scipy.special import owens_t
    from scipy.stats import chi2, norm

    s = np.sqrt(chi2.ppf((np.arange(SD_QUANTILES) + 0.5) / SD_QUANTILES, dof) / dof)
    h = factor * s
    rho = SHARED_VISIT_CORRELATION
    both = norm.sf(h) - 2.0 * owens_t(h, math.sqrt((1.0 - rho) / (1.0 + rho)))
    return float(2.0 * np.mean(both))


@functools.lru_cache(maxsize=256)
def confirmation_alpha(confirmations: int, dof: int, alpha: float = 0.05) -> float:
    """The two-sided per-comparison level at which a step and its confirmation are judged in a report of
    ``confirmations`` confirmable steps, their retest SD from ``dof`` pairs (0.01-0.02 for about 20 steps).

    The Student-t factor ``c`` whose :func:`confirmation_chance` is ``alpha / confirmations``, as the level
    ``2 P(t_dof > c)``; Student's t at that level gives back ``c``. The estimates' own uncertainty, where it is
    the larger, is judged at the same level with the normal quantile.
    """
    from scipy.optimize import brentq
    from scipy.stats import t

    target = alpha / max(confirmations, 1)
    factor = brentq(lambda c: confirmation_chance(c, dof) - target, 0.1, 100.0, xtol=1e-10)
    return float(2.0 * t.sf(factor, dof))
