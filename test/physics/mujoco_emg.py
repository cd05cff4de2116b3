"""Surface EMG envelopes of a MuJoCo patient: what an EMG amplifier would record of the torques the patient made.

Test support (not part of the installed package): ``mujoco_patient.patient_session`` calls it where the
:class:`~mujoco_patient.Patient` has ``emg``. Three channels, ``biceps`` (elbow flexor), ``triceps`` (elbow
extensor) and ``deltoid_anterior`` (shoulder flexor); the wrist's muscles are not recorded, so a wrist-only burst
shows in the torque alone. Each channel's raw signal is white Gaussian noise at 2 kHz whose RMS is the channel's
noise floor (a few uV; log-normal across channels) and, where its muscle works, the muscle's activity: its RMS
proportional to the part of its joint's imposed torque of its sign (flexors for positive, extensors for negative
torques), leading that torque by the electromechanical delay (Cavanagh and Komi, Eur J Appl Physiol 42:159-163,
1979: 30-100 ms). An amplifier's envelope of it: rectified, low-passed (second-order Butterworth, causal, 6 Hz),
sampled at 100 Hz.

Optionally one co-contraction: biceps and triceps active together with no net torque (nothing is applied in the
engine), which the torque cannot show and the EMG does.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import butter, sosfilt

__all__ = ["CHANNELS", "EmgRecording", "EmgTruth", "emg_envelopes"]

CHANNELS = ("biceps", "triceps", "deltoid_anterior")
# Each channel's joint and the sign of the torque its muscle makes (positive: flexion, raising the segment).
_MUSCLES = ((1, 1.0), (1, -1.0), (0, 1.0))
RAW_HZ = 2000.0


@dataclass(frozen=True, kw_only=True)
class EmgRecording:
    """The EMG a cell records of the patient.

    Attributes
    ----------
    rate_hz : the envelope's sample rate, Hz.
    lowpass_hz : the envelope filter's cut-off, Hz.
    floor_uv : the median over channels of the noise floor's RMS, uV.
    floor_spread : the log-normal sd of the floor across channels.
    uv_per_nm : (3,) each channel's activity RMS per Nm of its muscle's torque, uV/Nm (a biceps of 60 Nm at a
        maximal contraction of 600 uV RMS: 10 uV/Nm).
    lead_s : the EMG's lead over the torque it makes (electromechanical delay), s.
    cocontraction_s : the length of one co-contraction of biceps and triceps without net torque, s (0: none).
    cocontraction_uv : the RMS of each muscle's activity during it, uV.
    """

    rate_hz: float = 100.0
    lowpass_hz: float = 6.0
    floor_uv: float = 3.0
    floor_spread: float = 0.3
    uv_per_nm: tuple[float, float, float] = (10.0, 10.0, 12.0)
    lead_s: float = 0.05
    cocontraction_s: float = 0.0
    cocontraction_uv: float = 12.0


@dataclass(frozen=True, kw_only=True)
class EmgTruth:
    """The envelopes recorded and what made them.

    Attributes
    ----------
    t_s : (M,) envelope sample times, s since the recording's start.
    envelope_uv : (M, 3) the envelopes, uV.
    floor_uv : (3,) each channel's noise floor RMS, uV.
    cocontraction_s : the co-contraction's start and end, s, or None.
    cocontraction_active : (N,) bool at the engine's steps, inside the co-contraction.
    """

    t_s: np.ndarray
    envelope_uv: np.ndarray
    floor_uv: np.ndarray
    cocontraction_s: tuple[float, float] | None
    cocontraction_active: np.ndarray

    def to_json(self) -> dict[str, object]:
        """truth.json's ``patient.emg``."""
        return {
            "channels": list(CHANNELS),
            "floor_uv": self.floor_uv.tolist(),
            "cocontraction_s": None if self.cocontraction_s is None else list(self.cocontraction_s),
        }


def _cocontraction(
    rng: np.random.Generator, t_s: np.ndarray, busy: np.ndarray, duration_s: float
) -> tuple[float, float] | None:
    """A seeded stretch of ``duration_s`` within the middle 80 % of ``t_s`` (N,) clear of ``busy`` (N,) by 1 s
    (the first of 200 draws that is; else the last draw)."""
    if duration_s <= 0:
        return None
    span = float(t_s[-1])
    start = 0.0
    for _ in range(200):
        start = float(rng.uniform(0.1 * span, 0.9 * span - duration_s))
        near = (t_s > start - 1.0) & (t_s < start + duration_s + 1.0)
        if not busy[near].any():
            break
    return start, start + duration_s


def emg_envelopes(
    rng: np.random.Generator, t_s: np.ndarray, torque_nm: np.ndarray, busy: np.ndarray, recording: EmgRecording
) -> EmgTruth:
    """The envelopes of the patient's muscles over the recorded span.

    Parameters
    ----------
    rng : the EMG's own generator (the patient's other draws stay as without EMG).
    t_s : (N,) the engine's recorded step times, s (from 0).
    torque_nm : (N, 3) the involuntary joint torques imposed at those steps, Nm.
    busy : (N,) bool, inside an imposed burst (the co-contraction is placed clear of them).
    recording : the amplifier and the muscles.

    Returns
    -------
    EmgTruth
    """
    floor = recording.floor_uv * np.exp(recording.floor_spread * rng.standard_normal(len(CHANNELS)))
    stretch = _cocontraction(rng, t_s, busy, recording.cocontraction_s)
    raw_t = np.arange(0.0, float(t_s[-1]), 1.0 / RAW_HZ)
    co = np.zeros(raw_t.size)
    co_active = np.zeros(t_s.size, dtype=bool)
    if stretch is not None:
        # Hann ramps of 0.2 s at both ends: a contraction rises and falls, it does not switch.
        ramp = 0.2
        rise = np.clip((raw_t - stretch[0]) / ramp, 0.0, 1.0)
        fall = np.clip((stretch[1] - raw_t) / ramp, 0.0, 1.0)
        co = recording.cocontraction_uv * np.sin(0.5 * np.pi * np.minimum(rise, fall)) ** 2
        co_active = (t_s >= stretch[0]) & (t_s <= stretch[1])
    sos = butter(2, recording.lowpass_hz, fs=RAW_HZ, output="sos")
    step = round(RAW_HZ / recording.rate_hz)
    columns = []
    for c, (joint, sign) in enumerate(_MUSCLES):
        torque = np.interp(raw_t + recording.lead_s, t_s, torque_nm[:, joint])
        activity = recording.uv_per_nm[c] * np.maximum(sign * torque, 0.0) + (co if c < 2 else 0.0)
        raw = np.sqrt(floor[c] ** 2 + activity**2) * rng.standard_normal(raw_t.size)
        columns.append(sosfilt(sos, np.abs(raw))[::step])
    # The filter's run-in (its first tenth of a second starts from zero) is not recorded.
    keep = raw_t[::step] >= 0.5
    return EmgTruth(
        t_s=raw_t[::step][keep],
        envelope_uv=np.column_stack(columns)[keep],
        floor_uv=floor,
        cocontraction_s=stretch,
        cocontraction_active=co_active,
    )
