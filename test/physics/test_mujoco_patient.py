"""The patient cell's physics: what it imposes is what was asked, and a patient who adds nothing is the cell."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics-engine cell needs MuJoCo (pip install mujoco, the test extra)")

from mujoco_bag import record
from mujoco_cell import CellOptions, draw_arm, paper_sine
from mujoco_patient import (
    CompliantStrap,
    HandSlip,
    InvoluntaryActivity,
    Patient,
    SkinSliding,
    Spasticity,
    Tremor,
    TremorSite,
    patient_session,
)

from bsp_ros.core import model


def _options(duration_s: float = 20.0, speed: float = 0.03, seed: int = 3) -> CellOptions:
    return CellOptions(trajectory=paper_sine(speed), duration_s=duration_s, seed=seed)


def _contact_torques(session) -> np.ndarray:  # type: ignore[no-untyped-def]
    """(N, 3) -J^T F_end from the engine's noise-free wrench, Nm."""
    run = session.cell.run
    lengths = session.cell.truth["segments"]
    a = [lengths[s]["length_m"] for s in ("upper_arm", "forearm", "hand")]
    return model.contact_torques_nm(run.q_rad, a, run.wrench_world())


def test_a_patient_who_adds_nothing_records_the_cell_bit_for_bit() -> None:
    arm, options = draw_arm(2), _options(duration_s=5.0)
    plain = record(arm, options)
    patient = patient_session(arm, options, Patient())
    for a, b in (
        (plain.session.wrench.force_n, patient.cell.session.wrench.force_n),
        (plain.session.wrench.torque_nm, patient.cell.session.wrench.torque_nm),
        (plain.session.markers["hand"].position_m, patient.cell.session.markers["hand"].position_m),
        (plain.run.q_rad, patient.cell.run.q_rad),
    ):
        assert np.array_equal(a, b)
    assert patient.cell.truth["patient"] == {
        "description": dict.fromkeys(("activity", "spasticity", "tremor", "skin", "slip", "strap"))
    }


@pytest.mark.parametrize("share", [0.02, 0.20])
def test_activity_bursts_have_the_requested_share_of_gravity_torque_and_reach_the_sensor(share: float) -> None:
    arm, options = draw_arm(4), _options()
    relaxed = patient_session(arm, options, Patient())
    active = patient_session(arm, options, Patient(activity=InvoluntaryActivity(share_of_gravity=share)))
    imposed = active.imposed
    # The gravity torques the share refers to, independently: the relaxed run's measured torques minus friction.
    gravity, _ = relaxed.cell.run.torque_split_nm(every=20)
    gravity_rms = np.sqrt((gravity**2).mean(axis=0))
    rms = np.sqrt((imposed.activity_nm**2).mean(axis=0))
    assert np.allclose(rms / gravity_rms, share, rtol=0.02)
    # Bursty: the torque is zero outside the bursts, which cover part of the session only.
    assert 0.05 < imposed.activity_active.mean() < 0.9
    assert np.abs(imposed.activity_nm[~imposed.activity_active]).max() < 0.05 * np.abs(imposed.activity_nm).max()
    # Band-limited: almost no power above 2 Hz.
    spectrum = np.abs(np.fft.rfft(imposed.activity_nm[:, 1])) ** 2
    freq = np.fft.rfftfreq(imposed.t_s.size, 1e-3)
    assert spectrum[freq > 2.5].sum() < 1e-3 * spectrum.sum()
    # The sensor carries it: the measured joint torques differ from the relaxed arm's by the imposed ones
    # (the arm's own friction and inertia, which the torques change slightly, within 10 % of the RMS).
    difference = _contact_torques(active) - _contact_torques(relaxed)
    assert np.sqrt(((difference + imposed.activity_nm) ** 2).mean(axis=0)).max() < 0.1 * rms.max()


def test_the_stretch_reflex_is_zero_below_its_threshold_and_follows_the_stretch_after_its_delay() -> None:
    arm = draw_arm(5)
    reflex = Spasticity(gain_nm_s_per_rad=4.0, threshold_rad_s=0.02, delay_s=0.05)
    slow = patient_session(arm, _options(speed=0.03), Patient(spasticity=reflex))  # elbow peak 0.01 rad/s
    assert not slow.imposed.reflex_active.any()
    assert np.array_equal(slow.cell.run.q_rad, patient_session(arm, _options(speed=0.03), Patient()).cell.run.q_rad)

    fast = patient_session(arm, _options(speed=0.12), Patient(spasticity=reflex))  # elbow peak 0.04 rad/s
    imposed, run = fast.imposed, fast.cell.run
    assert 0.05 < imposed.reflex_active.mean() < 0.5
    stretch = -run.qdot_rad_s[:, 1]
    delay = 50  # steps of 1 ms
    expected = 4.0 * np.maximum(0.0, stretch[:-delay] - 0.02)
    assert np.abs(imposed.reflex_nm[delay:, 1] - expected).max() < 1e-12
    # Only while the elbow extends (flexors stretched), and only the elbow.
    assert (stretch[:-delay][imposed.reflex_active[delay:]] > 0.02).all()
    assert not imposed.reflex_nm[:, [0, 2]].any()
    assert fast.cell.truth["patient"]["spasticity"]["active_s"]


def test_sliding_markers_move_by_the_requested_mm_along_their_segment() -> None:
    arm, options = draw_arm(6), _options(duration_s=15.0)
    fixed = patient_session(arm, options, Patient()).cell.run
    wanted_mm = (15.0, 6.0, 3.0, 0.0)
    slid = patient_session(arm, options, Patient(skin=SkinSliding(range_mm=wanted_mm)))
    phi = np.cumsum(fixed.q_rad, axis=1)
    for k, segment in enumerate((0, 1, 2, 2)):
        moved = slid.cell.run.markers_m[:, k] - fixed.markers_m[:, k]
        axis = np.column_stack((np.zeros_like(phi[:, 0]), np.cos(phi[:, segment]), np.sin(phi[:, segment])))
        along = np.einsum("ni,ni->n", moved, axis)
        assert abs(1e3 * np.ptp(along) - wanted_mm[k]) < 1e-6
        assert np.abs(moved - along[:, None] * axis).max() < 1e-12  # along the segment only
    # The driving joint's angle sets the slide: the shoulder marker is distal where the shoulder angle is highest.
    assert np.argmax(slid.imposed.marker_slide_m[:, 0]) == np.argmax(slid.cell.run.q_command_rad[:, 0])
    assert slid.cell.truth["patient"]["skin"]["range_mm"] == pytest.approx(list(wanted_mm))


def test_a_slipping_hand_moves_the_contact_point_away_from_the_hand_marker_by_the_requested_mm() -> None:
    arm, options = draw_arm(7), _options(duration_s=20.0)
    session = patient_session(arm, options, Patient(slip=HandSlip(total_mm=12.0, events=2, slip_s=0.5)))
    run = session.cell.run
    # The stiff strap holds the contact point at the handle, which the robot moves along the commanded angles'
    # forward kinematics; the slip is the handle's distance from the hand marker along the hand.
    phi_command = np.cumsum(run.q_command_rad, axis=1)
    lengths = np.asarray(arm.lengths_m)
    handle_yz = np.array(options.shoulder_m[1:]) + np.column_stack(
        ((lengths * np.cos(phi_command)).sum(axis=1), (lengths * np.sin(phi_command)).sum(axis=1))
    )
    phi_hand = np.cumsum(run.q_rad, axis=1)[:, 2]
    hand_axis = np.column_stack((np.cos(phi_hand), np.sin(phi_hand)))
    along = np.einsum("ni,ni->n", handle_yz - run.markers_m[:, 3, 1:], hand_axis)
    assert abs(along[0]) < 1e-4
    assert abs(1e3 * along[-1] - 12.0) < 0.1
    assert np.abs(along - session.imposed.slip_m).max() < 2e-4  # the strap lags a slip by a fraction of a mm
    assert session.cell.truth["patient"]["slip"]["final_mm"] == pytest.approx(12.0)
    # The hand marker stays on the hand.
    assert np.ptp(np.linalg.norm(run.markers_m[:, 3] - run.markers_m[:, 2], axis=1)) < 1e-9


def test_a_compliant_strap_sags_millimetres_and_degrees_under_the_arm() -> None:
    arm, options = draw_arm(8), _options(duration_s=5.0)
    stiff = patient_session(arm, options, Patient()).imposed
    soft = patient_session(arm, options, Patient(strap=CompliantStrap())).imposed
    assert stiff.weld_sag_m.max() < 2e-4
    assert 2e-3 < soft.weld_sag_m.mean() < 4e-3
    assert 1.0 < np.degrees(soft.weld_sag_rad.mean()) < 2.5


@pytest.mark.parametrize("site", list(TremorSite))
def test_a_tremor_shows_in_the_wrench_at_its_frequency(site: TremorSite) -> None:
    arm, options = draw_arm(9), _options(duration_s=20.0)
    relaxed = patient_session(arm, options, Patient())
    session = patient_session(arm, options, Patient(tremor=Tremor(frequency_hz=5.0, site=site)))
    assert abs(session.cell.truth["patient"]["tremor"]["frequency_hz"] - 5.0) < 0.1

    def spectrum(s) -> np.ndarray:  # type: ignore[no-untyped-def]
        force = s.cell.run.wrench_world()[:, 0]
        return np.abs(np.fft.rfft(force - force.mean()))

    freq = np.fft.rfftfreq(session.imposed.t_s.size, 1e-3)
    shaking, still = spectrum(session), spectrum(relaxed)
    band = (freq > 4.0) & (freq < 6.0)
    above = freq > 1.0  # the protocol's own motion lies below
    assert 4.5 < freq[above][np.argmax(shaking[above])] < 5.5
    assert shaking[band].max() > 10.0 * still[band].max()
