"""A scipy-designed low-order IIR filter stepped one sample at a time, for live streams."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from scipy import signal


class StreamingFilter:
    """Filters several channels sample by sample with the filter of ``sos``, starting in steady state.

    The same output as ``scipy.signal.sosfilt`` with ``zi = sosfilt_zi(sos) * first_sample``, but
    stepped in the state-space form of ``scipy.signal.tf2ss``: a few microseconds per sample, where a
    one-sample ``sosfilt`` call spends ~90 us validating its arguments. Meant for the low orders (2-4)
    of live angle filters; a high-order transfer function would be ill-conditioned in this form.

    Parameters
    ----------
    sos : (S, 6) second-order sections, e.g. from ``scipy.signal.butter(..., output="sos")``.
    """

    def __init__(self, sos: npt.ArrayLike) -> None:
        b, a = signal.sos2tf(np.asarray(sos, dtype=np.float64))
        a_ss, b_ss, c_ss, d_ss = signal.tf2ss(b, a)
        self._a = np.asarray(a_ss, dtype=np.float64)
        self._b = np.asarray(b_ss, dtype=np.float64)[:, 0]
        self._c = np.asarray(c_ss, dtype=np.float64)[0]
        self._d = float(np.asarray(d_ss)[0, 0])
        # State per unit constant input in steady state, x = (I - A)^-1 B: starting there avoids the
        # filter's step response on the first sample (what sosfilt_zi does for sosfilt).
        self._steady = np.linalg.solve(np.eye(self._a.shape[0]) - self._a, self._b)
        self._x: np.ndarray | None = None

    def reset(self) -> None:
        """Forget the state: the next sample starts the filter in steady state again."""
        self._x = None

    def step(self, u: np.ndarray) -> np.ndarray:
        """Filter one sample.

        Parameters
        ----------
        u : (C,) one value per channel.

        Returns
        -------
        (C,) the filtered values.
        """
        if self._x is None:
            self._x = np.outer(self._steady, u)
        y = self._c @ self._x + self._d * u
        self._x = self._a @ self._x + np.outer(self._b, u)
        return np.asarray(y)
