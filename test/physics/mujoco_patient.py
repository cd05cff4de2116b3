"""A patient in the MuJoCo cell: what a real arm adds to the relaxed one, each with the truth of what was imposed.

Test support (not part of the installed package): ``test/physics/test_mujoco_patient.py`` and
``bench/patients.py`` import it. The relaxed arm, its truth (segment parameters and RELAXED passive moments) and
the bag are those of ``mujoco_cell`` and ``mujoco_bag``; a :class:`Patient` adds, each optional:

- :class:`InvoluntaryActivity`: joint torque bursts the patient does not intend (associated reactions, flexion
  synergy: Dewald and Beer, Muscle Nerve 24:273-283, 2001; Bhakta et al., Clin Rehabil 15:195-206, 2001),
  band-limited white noise (0.05-2 Hz) under a bursty envelope, its RMS over the session a share of each joint's
  RMS gravity torque (the sweep 2/5/10/20 %: relaxation is instructed, not verified, and EMG-quiet is a threshold
  of baseline + k sd, not zero);
- :class:`Spasticity`: the elbow flexors' velocity-dependent stretch reflex (Lance 1980): after a delay (30-60 ms,
  the long-latency stretch reflex), a flexor torque ``gain * max(0, stretch speed - threshold)`` while the elbow is
  extended. McPherson, Stienen, Schmit and Dewald (Exp Brain Res 237:121-135, 2019) stretched paretic elbows at
  15-150 deg/s; reflex torques of a few Nm at 100 deg/s give gains of 2-5 Nm s/rad. Thresholds fall with the
  severity (NeuroFlexor: Lindberg et al., Neurorehabil Neural Repair 25:617-625, 2011, separates the neural part
  at 5 and 236 deg/s); the default threshold lies within a robot's slow sweep (0.02 rad/s, 1.1 deg/s) so that the
  paper's speed (elbow peak 0.01 rad/s) stays below it and four times faster crosses it;
- :class:`Tremor`: a 4-6 Hz oscillation (Parkinson's rest tremor 4-6 Hz, essential tremor 4-12 Hz; propagation
  through the limb's joints: Davidson and Charles, Ann Biomed Eng 45:1133-1147, 2017) with a slowly wandering
  amplitude and frequency, as joint torques or as the handle shaken (a compliant robot handle moved by the
  tremor);
- :class:`SkinSliding`: skin markers that slide along their segment with the joint angle (soft-tissue artefact:
  Leardini et al., Gait Posture 21:212-225, 2005, review it; the acromion marker most, 1-2 cm over the humeral
  elevation; 3-20 mm);
- :class:`HandSlip`: the hand's contact point drifting 5-15 mm along the hand in the handle during the session
  (the wrench then acts where the hand marker is not);
- :class:`CompliantStrap`: a soft weld (palm tissue: about 3 mm and 1-2 deg of sag under the arm's weight), so
  the hand lags the handle at each reversal and dry joint friction sticks there.

:func:`patient_session` runs the engine with a :class:`PatientHook` (``mujoco_cell.EngineHook``), slides the
markers, records the bag's streams (``mujoco_bag.record``) and returns the imposed truth (:class:`Imposed`):
the active joint torques per step, when the reflex was active, the slip in mm, the tremor's frequency, the
strap's sag; its :meth:`Imposed.to_json` is written as truth.json's ``patient`` key.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

import mujoco
import numpy as np
from mujoco_bag import CellSession, record
from mujoco_cell import ArmParams, CellOptions, EngineRun, mjcf_text, run_engine
from mujoco_emg import CHANNELS, EmgRecording, EmgTruth, emg_envelopes

from bsp_ros.core.streams import EmgSeries

_MARKER_JOINT = (0, 1, 2, 2)  # the joint whose angle slides each marker (shoulder, elbow, wrist, hand)
_MARKER_SEGMENT = (0, 1, 2, 2)  # the segment each marker is fixed to
ELBOW = 1


@dataclass(frozen=True, kw_only=True)
class InvoluntaryActivity:
    """Joint torque bursts the patient does not intend.

    Attributes
    ----------
    share_of_gravity : RMS over the session of each joint's torque over that joint's RMS gravity torque (0.05: 5 %).
    band_hz : (low, high) pass band of the carrier, Hz.
    bursts_per_min : mean number of bursts a minute (Poisson; at least one per session).
    burst_s : (shortest, longest) burst duration, s (uniform); each burst a Hann window.
    """

    share_of_gravity: float = 0.05
    band_hz: tuple[float, float] = (0.05, 2.0)
    bursts_per_min: float = 6.0
    burst_s: tuple[float, float] = (2.0, 8.0)


@dataclass(frozen=True, kw_only=True)
class Spasticity:
    """The elbow flexors' stretch reflex: ``gain * max(0, stretch speed(t - delay) - threshold)``, flexing.

    Attributes
    ----------
    gain_nm_s_per_rad : reflex torque per rad/s of stretch speed above the threshold, Nm s/rad.
    threshold_rad_s : stretch (elbow extension) speed the reflex starts at, rad/s.
    delay_s : the reflex's latency, s (a whole number of engine steps).
    """

    gain_nm_s_per_rad: float = 4.0
    threshold_rad_s: float = 0.02
    delay_s: float = 0.04


class TremorSite(StrEnum):
    """Where a tremor acts."""

    JOINTS = "joints"
    """Joint torques at the tremor frequency."""
    HANDLE = "handle"
    """The robot's handle shaken in the sagittal plane (the tremor moving a compliant handle)."""


@dataclass(frozen=True, kw_only=True)
class Tremor:
    """A 4-6 Hz tremor with a slowly wandering amplitude (+-30 %, 0.2 Hz) and frequency (+-0.3 Hz).

    Attributes
    ----------
    frequency_hz : mean frequency, Hz.
    site : joint torques or the handle shaken.
    torque_amplitude_nm : (3,) peak joint torque per joint, Nm (site JOINTS).
    handle_amplitude_m : peak handle displacement along ``handle_direction_deg`` in the y-z plane, m (site HANDLE).
    handle_direction_deg : the shaking direction from world +y toward +z, deg.
    """

    frequency_hz: float = 5.0
    site: TremorSite = TremorSite.JOINTS
    torque_amplitude_nm: tuple[float, float, float] = (0.3, 0.3, 0.1)
    handle_amplitude_m: float = 5e-4
    handle_direction_deg: float = 60.0


@dataclass(frozen=True, kw_only=True)
class SkinSliding:
    """Markers sliding along their segment, linear in a joint's angle.

    Attributes
    ----------
    range_mm : (4,) peak-to-peak slide over the session's range of the driving joint, per marker (shoulder, elbow,
        wrist, hand), mm; the shoulder marker (acromion) slides with the shoulder angle, the elbow's with the elbow,
        the wrist's and hand's with the wrist. Distal with the angle rising.
    """

    range_mm: tuple[float, float, float, float] = (12.0, 6.0, 3.0, 3.0)


@dataclass(frozen=True, kw_only=True)
class HandSlip:
    """The contact point drifting along the hand (distal positive) during the session.

    Attributes
    ----------
    total_mm : the drift at the session's end, mm.
    events : the number of slips (each a smooth step over ``slip_s`` at a seeded time); 0: a steady drift.
    slip_s : the duration of one slip, s.
    """

    total_mm: float = 10.0
    events: int = 3
    slip_s: float = 0.5


@dataclass(frozen=True, kw_only=True)
class CompliantStrap:
    """A soft weld between the hand's contact point and the handle (MuJoCo ``solref`` of the strap).

    The defaults sag 2.6-2.7 mm and 1.1-1.8 deg on average (up to 5 mm and 2.8 deg) under the arms of seeds 0-2
    of ``draw_arm`` on the paper's sines (measured in ``Imposed.weld_sag_m``, ``weld_sag_rad``).

    Attributes
    ----------
    timeconst_s : the weld's time constant, s (the cell's strap: 0.002); larger is softer.
    dampratio : its damping ratio.
    torquescale : the weld's rotational over translational stiffness (MuJoCo ``torquescale``).
    """

    timeconst_s: float = 0.1
    dampratio: float = 1.0
    torquescale: float = 0.35


@dataclass(frozen=True, kw_only=True)
class Patient:
    """What a real patient adds to the relaxed arm; ``Patient()`` adds nothing (the cell bit for bit)."""

    activity: InvoluntaryActivity | None = None
    spasticity: Spasticity | None = None
    tremor: Tremor | None = None
    skin: SkinSliding | None = None
    slip: HandSlip | None = None
    strap: CompliantStrap | None = None
    emg: EmgRecording | None = None  # recorded by the cell (mujoco_emg.py), nothing acts in the engine

    @property
    def in_engine(self) -> bool:
        """Whether anything acts in the engine (all but the skin markers, which slide after the run)."""
        return any(x is not None for x in (self.activity, self.spasticity, self.tremor, self.slip, self.strap))


def typical_stroke_arm() -> Patient:
    """A typical stroke arm's patient part (use with ``draw_arm(seed, springs=True)``): mild activity (2 %), elbow
    spasticity at the default gain and threshold, sliding skin markers."""
    return Patient(activity=InvoluntaryActivity(share_of_gravity=0.02), spasticity=Spasticity(), skin=SkinSliding())


@dataclass(frozen=True, kw_only=True)
class Imposed:
    """What the patient did during the recorded span (t >= 0): the truth a detector is checked against.

    Attributes
    ----------
    t_s : (N,) step times, s.
    activity_nm, reflex_nm, tremor_nm : (N, 3) joint torques of each kind, Nm (zero where absent).
    gravity_rms_nm : (3,) each joint's RMS gravity torque on the commanded path, Nm.
    activity_active : (N,) bool, inside a burst (envelope above 5 % of its peak).
    reflex_active : (N,) bool, the reflex torque nonzero.
    handle_offset_m : (N, 3) the handle's tremor displacement, m.
    slip_m : (N,) the contact point's drift along the hand, m.
    marker_slide_m : (N, 4) each marker's slide along its segment, m.
    weld_sag_m, weld_sag_rad : (N,) the strap's deflection (contact body against handle), m and rad.
    tremor_frequency_hz : (N,) the tremor's instantaneous frequency, Hz (NaN without a tremor).
    patient : the description that was run.
    emg : the EMG envelopes recorded and what made them (``patient.emg``), else None.
    """

    t_s: np.ndarray
    activity_nm: np.ndarray
    reflex_nm: np.ndarray
    tremor_nm: np.ndarray
    gravity_rms_nm: np.ndarray
    activity_active: np.ndarray
    reflex_active: np.ndarray
    handle_offset_m: np.ndarray
    slip_m: np.ndarray
    marker_slide_m: np.ndarray
    weld_sag_m: np.ndarray
    weld_sag_rad: np.ndarray
    tremor_frequency_hz: np.ndarray
    patient: Patient = field(repr=False)
    emg: EmgTruth | None = field(default=None, repr=False)

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready summary: per kind what was imposed, its size and when (truth.json's ``patient`` key)."""
        p = self.patient
        out: dict[str, Any] = {"description": _description(p)}
        if p.activity is not None:
            rms = _rms(self.activity_nm)
            out["activity"] = {
                "rms_nm": rms.tolist(),
                "share_of_gravity": (rms / self.gravity_rms_nm).tolist(),
                "gravity_rms_nm": self.gravity_rms_nm.tolist(),
                "active_fraction": float(self.activity_active.mean()),
                "bursts_s": _intervals(self.t_s, self.activity_active),
            }
        if p.spasticity is not None:
            out["spasticity"] = {
                "peak_nm": float(np.abs(self.reflex_nm[:, ELBOW]).max()),
                "rms_nm": float(_rms(self.reflex_nm)[ELBOW]),
                "active_fraction": float(self.reflex_active.mean()),
                "active_s": _intervals(self.t_s, self.reflex_active),
            }
        if p.tremor is not None:
            out["tremor"] = {
                "site": str(p.tremor.site),
                "frequency_hz": float(np.nanmean(self.tremor_frequency_hz)),
                "torque_rms_nm": _rms(self.tremor_nm).tolist(),
                "handle_rms_m": float(_rms(np.linalg.norm(self.handle_offset_m, axis=1))),
            }
        if p.skin is not None:
            slide = self.marker_slide_m
            out["skin"] = {"range_mm": (1e3 * (slide.max(axis=0) - slide.min(axis=0))).tolist()}
        if p.slip is not None:
            out["slip"] = {"final_mm": float(1e3 * self.slip_m[-1]), "max_mm": float(1e3 * np.abs(self.slip_m).max())}
        if self.emg is not None:
            out["emg"] = self.emg.to_json()
        if p.strap is not None:
            out["strap"] = {
                "sag_mean_mm": float(1e3 * self.weld_sag_m.mean()),
                "sag_max_mm": float(1e3 * self.weld_sag_m.max()),
                "sag_mean_deg": float(np.degrees(self.weld_sag_rad.mean())),
                "sag_max_deg": float(np.degrees(self.weld_sag_rad.max())),
            }
        return out


def _description(p: Patient) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for f in dataclasses.fields(p):
        value = getattr(p, f.name)
        if f.name == "emg" and value is None:
            continue  # recorded, not imposed: a session without it keeps the truth it had
        out[f.name] = None if value is None else {k: _plain(v) for k, v in dataclasses.asdict(value).items()}
    return out


def _plain(value: Any) -> Any:
    if isinstance(value, StrEnum):
        return str(value)
    if isinstance(value, tuple):
        return list(value)
    return value


def _rms(x: np.ndarray) -> np.ndarray:
    return np.sqrt(np.mean(np.square(x), axis=0))


def _intervals(t_s: np.ndarray, active: np.ndarray) -> list[list[float]]:
    """[start, end] times (s) of each run of ``active``."""
    edges = np.diff(np.concatenate(([0], active.astype(np.int8), [0])))
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return [[float(t_s[a]), float(t_s[b])] for a, b in zip(starts, ends, strict=True)]


def gravity_rms_nm(arm: ArmParams, options: CellOptions, every: int = 20) -> np.ndarray:
    """(3,) each joint's RMS gravity torque along the commanded path of the recorded span, Nm (MuJoCo's RNE)."""
    model = mujoco.MjModel.from_xml_string(mjcf_text(arm, options))
    data = mujoco.MjData(model)
    t = np.arange(0.0, options.duration_s, every * options.timestep_s)
    torque = np.empty((t.size, 3))
    for i, q in enumerate(options.trajectory.angles_rad(t)):
        data.qpos[:] = q
        data.qvel[:] = 0.0
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
        mujoco.mj_rne(model, data, 0, torque[i])
    return np.asarray(_rms(torque))


def band_limited(rng: np.random.Generator, n: int, dt_s: float, band_hz: tuple[float, float]) -> np.ndarray:
    """(n,) white Gaussian noise kept only within ``band_hz`` (its Fourier coefficients elsewhere zeroed), unit RMS."""
    spectrum = np.fft.rfft(rng.standard_normal(n))
    freq = np.fft.rfftfreq(n, dt_s)
    spectrum[(freq < band_hz[0]) | (freq > band_hz[1])] = 0.0
    x = np.fft.irfft(spectrum, n)
    return np.asarray(x / np.sqrt(np.mean(x**2)))


def burst_envelope(
    rng: np.random.Generator, t_s: np.ndarray, bursts_per_min: float, burst_s: tuple[float, float]
) -> np.ndarray:
    """(N,) a sum of Hann-window bursts (Poisson count, uniform times, durations and heights 0.5-1)."""
    span = float(t_s[-1] - t_s[0])
    count = max(1, int(rng.poisson(bursts_per_min * span / 60.0)))
    envelope = np.zeros_like(t_s)
    for _ in range(count):
        length = rng.uniform(*burst_s)
        start = rng.uniform(t_s[0], t_s[-1] - length)
        phase = (t_s - start) / length
        inside = (phase >= 0.0) & (phase <= 1.0)
        envelope[inside] += rng.uniform(0.5, 1.0) * np.sin(np.pi * phase[inside]) ** 2
    return envelope


def slip_profile(rng: np.random.Generator, t_s: np.ndarray, slip: HandSlip) -> np.ndarray:
    """(N,) the contact point's drift along the hand, m: ``events`` smooth steps at seeded times, or a steady ramp."""
    total = 1e-3 * slip.total_mm
    start, end = 0.0, float(t_s[-1])
    if slip.events == 0:
        return np.asarray(total * np.clip((t_s - start) / (end - start), 0.0, 1.0))
    times = np.sort(rng.uniform(start + 0.1 * end, 0.9 * end, slip.events))
    sizes = rng.uniform(0.5, 1.0, slip.events)
    sizes *= total / sizes.sum()
    drift = np.zeros_like(t_s)
    for when, size in zip(times, sizes, strict=True):
        phase = np.clip((t_s - when) / slip.slip_s, 0.0, 1.0)
        drift += size * (phase - np.sin(2.0 * np.pi * phase) / (2.0 * np.pi))  # smooth in speed at both ends
    return drift


class PatientHook:
    """The patient in the engine (``mujoco_cell.EngineHook``): joint torques, a shaken handle, a moving contact
    point, a soft strap. Its arrays (every step, the unrecorded lead-in first) are the imposed truth."""

    def __init__(self, arm: ArmParams, options: CellOptions, patient: Patient) -> None:
        self.arm, self.options, self.patient = arm, options, patient
        self.rng = np.random.default_rng(np.random.SeedSequence([options.seed, 31]))
        self.gravity_rms_nm = gravity_rms_nm(arm, options) if patient.activity is not None else np.zeros(3)

    def prepare(self, model: Any, data: Any, t_s: np.ndarray) -> None:
        """Draw every seeded signal over ``t_s`` and soften the strap."""
        n, dt = t_s.size, self.options.timestep_s
        p, rng = self.patient, self.rng
        recorded = t_s >= 0.0
        self.t_s = t_s
        self.activity_nm = np.zeros((n, 3))
        self.activity_active = np.zeros(n, dtype=bool)
        if p.activity is not None:
            envelope = burst_envelope(rng, t_s, p.activity.bursts_per_min, p.activity.burst_s)
            for j in range(3):
                self.activity_nm[:, j] = envelope * band_limited(rng, n, dt, p.activity.band_hz)
            scale = p.activity.share_of_gravity * self.gravity_rms_nm / _rms(self.activity_nm[recorded])
            self.activity_nm *= scale
            self.activity_active = envelope > 0.05 * envelope.max()
        self.tremor_nm = np.zeros((n, 3))
        self.handle_offset_m = np.zeros((n, 3))
        self.tremor_frequency_hz = np.full(n, np.nan)
        if p.tremor is not None:
            self._draw_tremor(p.tremor, t_s)
        self.slip_m = slip_profile(rng, t_s, p.slip) if p.slip is not None else np.zeros(n)
        self.reflex_nm = np.zeros((n, 3))
        self.stretch_rad_s = np.zeros(n)
        if p.spasticity is not None:
            self.delay_steps = round(p.spasticity.delay_s / dt)
            if abs(self.delay_steps * dt - p.spasticity.delay_s) > 1e-9:
                raise ValueError(f"delay_s {p.spasticity.delay_s!r} is not a whole number of {dt!r} s steps")
        self.contact_id = model.body("hand_contact").id
        self.contact_pos = model.body_pos[self.contact_id].copy()
        if p.strap is not None:
            strap = model.equality("strap").id
            model.eq_solref[strap] = (p.strap.timeconst_s, p.strap.dampratio)
            model.eq_data[strap, 10] = p.strap.torquescale

    def _draw_tremor(self, tremor: Tremor, t_s: np.ndarray) -> None:
        dt = self.options.timestep_s
        n = t_s.size
        wander = band_limited(self.rng, n, dt, (0.02, 0.2))
        frequency = tremor.frequency_hz + 0.3 * np.clip(wander / 2.0, -1.0, 1.0)
        amplitude = 1.0 + 0.3 * np.clip(band_limited(self.rng, n, dt, (0.02, 0.2)) / 2.0, -1.0, 1.0)
        phase = 2.0 * np.pi * np.cumsum(frequency) * dt
        wave = amplitude * np.sin(phase)
        self.tremor_frequency_hz = frequency
        if tremor.site == TremorSite.JOINTS:
            self.tremor_nm = wave[:, None] * np.asarray(tremor.torque_amplitude_nm)
        else:
            angle = np.radians(tremor.handle_direction_deg)
            direction = np.array([0.0, np.cos(angle), np.sin(angle)])
            self.handle_offset_m = tremor.handle_amplitude_m * wave[:, None] * direction

    def before_step(self, k: int, model: Any, data: Any) -> None:
        """Apply step ``k``'s torques, handle offset and contact point."""
        p = self.patient
        if p.spasticity is not None:
            self.stretch_rad_s[k] = -data.qvel[ELBOW]  # elbow extension stretches its flexors
            if k >= self.delay_steps:
                excess = self.stretch_rad_s[k - self.delay_steps] - p.spasticity.threshold_rad_s
                self.reflex_nm[k, ELBOW] = p.spasticity.gain_nm_s_per_rad * max(0.0, excess)
        data.qfrc_applied[:] = self.activity_nm[k] + self.reflex_nm[k] + self.tremor_nm[k]
        if p.tremor is not None and p.tremor.site == TremorSite.HANDLE:
            data.mocap_pos[0] += self.handle_offset_m[k]
        if p.slip is not None:
            model.body_pos[self.contact_id, 1] = self.contact_pos[1] + self.slip_m[k]


def marker_slide_m(run: EngineRun, options: CellOptions, skin: SkinSliding) -> np.ndarray:
    """(N, 4) each marker's slide along its segment, m: ``range_mm`` times the driving joint's commanded angle
    relative to its session range, centred on the range's middle."""
    q = run.q_command_rad
    slide = np.zeros((q.shape[0], 4))
    for k, j in enumerate(_MARKER_JOINT):
        low, high = q[:, j].min(), q[:, j].max()
        if high > low:
            slide[:, k] = 1e-3 * skin.range_mm[k] * ((q[:, j] - low) / (high - low) - 0.5)
    return slide


def slid_markers(run: EngineRun, slide_m: np.ndarray) -> np.ndarray:
    """(N, 4, 3) the engine's marker positions moved by ``slide_m`` along each marker's segment axis (world)."""
    phi = np.cumsum(run.q_rad, axis=1) + run.trunk_tilt_rad
    markers = run.markers_m.copy()
    for k, segment in enumerate(_MARKER_SEGMENT):
        axis = np.column_stack((np.zeros_like(phi[:, 0]), np.cos(phi[:, segment]), np.sin(phi[:, segment])))
        markers[:, k] += slide_m[:, k, None] * axis
    return markers


@dataclass(frozen=True)
class PatientSession:
    """A recorded session of a patient: the cell's session (truth.json with a ``patient`` key) and the imposed truth."""

    cell: CellSession
    imposed: Imposed


def patient_session(arm: ArmParams, options: CellOptions, patient: Patient) -> PatientSession:
    """Run the cell with ``patient`` and record it (seeded by ``options.seed``; the patient's draws apart from
    the sensor's, so the same seed gives the same noise with and without a patient)."""
    hook = PatientHook(arm, options, patient)
    run = run_engine(arm, options, hook if patient.in_engine else None)
    n_lead = round(options.lead_in_s / options.timestep_s)
    n = run.t_s.size
    slide = marker_slide_m(run, options, patient.skin) if patient.skin is not None else np.zeros((n, 4))
    if patient.skin is not None:
        run = dataclasses.replace(run, markers_m=slid_markers(run, slide))
    cell = record(arm, options, run)
    rec = slice(n_lead, None)

    def part(name: str, shape: tuple[int, ...], dtype: type = float) -> np.ndarray:
        value = getattr(hook, name, None)
        return np.zeros(shape, dtype=dtype) if value is None else np.asarray(value[rec])

    reflex = part("reflex_nm", (n, 3))
    imposed = Imposed(
        t_s=run.t_s,
        activity_nm=part("activity_nm", (n, 3)),
        reflex_nm=reflex,
        tremor_nm=part("tremor_nm", (n, 3)),
        gravity_rms_nm=hook.gravity_rms_nm,
        activity_active=part("activity_active", (n,), bool),
        reflex_active=reflex[:, ELBOW] > 0.0,
        handle_offset_m=part("handle_offset_m", (n, 3)),
        slip_m=part("slip_m", (n,)),
        marker_slide_m=slide,
        weld_sag_m=run.weld_drift_m,
        weld_sag_rad=run.weld_drift_rad,
        tremor_frequency_hz=part("tremor_frequency_hz", (n,)) if patient.tremor is not None else np.full(n, np.nan),
        patient=patient,
    )
    if patient.emg is not None:
        imposed = _with_emg(cell, imposed, options, patient.emg)
    cell.truth["patient"] = imposed.to_json()
    return PatientSession(cell, imposed)


def _with_emg(cell: CellSession, imposed: Imposed, options: CellOptions, recording: EmgRecording) -> Imposed:
    """``imposed`` with the EMG of its torques (its own seeded draws), the envelopes put into the cell's session."""
    rng = np.random.default_rng(np.random.SeedSequence([options.seed, 37]))
    truth = emg_envelopes(rng, imposed.t_s, imposed.activity_nm, imposed.activity_active, recording)
    t_ns = np.int64(options.start_ns) + np.round(truth.t_s * 1e9).astype(np.int64)
    cell.session = dataclasses.replace(
        cell.session, emg=EmgSeries(t_ns=t_ns, envelope=truth.envelope_uv, channels=CHANNELS)
    )
    return dataclasses.replace(imposed, emg=truth)


__all__ = [
    "CompliantStrap",
    "EmgRecording",
    "HandSlip",
    "Imposed",
    "InvoluntaryActivity",
    "Patient",
    "PatientHook",
    "PatientSession",
    "SkinSliding",
    "Spasticity",
    "Tremor",
    "TremorSite",
    "band_limited",
    "burst_envelope",
    "gravity_rms_nm",
    "marker_slide_m",
    "patient_session",
    "slid_markers",
    "slip_profile",
    "typical_stroke_arm",
]
