"""The MuJoCo patient's EMG: envelopes of the torques it made (by muscle and sign, leading them), and through
`bsp identify` a co-contraction without net torque, which the torque cannot show, left out and named."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mujoco", reason="the physics-engine cell needs MuJoCo (pip install mujoco, the test extra)")

from mujoco_bag import write_bag
from mujoco_cell import CellOptions, draw_arm, paper_sine
from mujoco_emg import EmgRecording
from mujoco_patient import InvoluntaryActivity, Patient, patient_session

from bsp_ros.cli import main


def test_the_envelopes_follow_the_muscles_that_make_the_torque() -> None:
    arm = draw_arm(4)
    options = CellOptions(trajectory=paper_sine(0.03), duration_s=30.0, seed=4)
    patient = Patient(activity=InvoluntaryActivity(share_of_gravity=0.1), emg=EmgRecording(cocontraction_s=3.0))
    session = patient_session(arm, options, patient)
    imposed, emg = session.imposed, session.cell.session.emg
    assert emg is not None and imposed.emg is not None
    assert emg.channels == ("biceps", "triceps", "deltoid_anterior")
    assert 99.0 < 1e9 / np.median(np.diff(emg.t_ns)) < 101.0
    t_s = (emg.t_ns - options.start_ns) * 1e-9
    elbow = np.interp(t_s, imposed.t_s, imposed.activity_nm[:, 1])
    quiet = ~np.interp(t_s, imposed.t_s, imposed.activity_active | imposed.emg.cocontraction_active).astype(bool)
    # quiet: the rectified floor's mean, sqrt(2/pi) of its RMS, within the 6 Hz envelope's few percent
    floor = np.sqrt(2.0 / np.pi) * imposed.emg.floor_uv
    np.testing.assert_allclose(np.median(emg.envelope[quiet], axis=0), floor, rtol=0.03)
    # the biceps rises with the elbow's flexing torque, the triceps with its extending torque
    flexing, extending = elbow > 0.3 * elbow.max(), elbow < 0.3 * elbow.min()
    assert np.median(emg.envelope[flexing, 0]) > 2 * floor[0] > np.median(emg.envelope[extending, 0])
    assert np.median(emg.envelope[extending, 1]) > 2 * floor[1] > np.median(emg.envelope[flexing, 1])
    # the co-contraction: biceps and triceps together, no torque applied
    start, end = imposed.emg.cocontraction_s or (0.0, 0.0)
    inside = (t_s > start + 0.5) & (t_s < end - 0.2)
    assert (emg.envelope[inside, :2] > 2 * floor[:2]).all()
    assert np.abs(np.interp(t_s[inside], imposed.t_s, imposed.activity_nm[:, 1])).max() < 1e-12


def _identify(bag: Path, out: Path, *extra: str) -> tuple[int, dict]:
    code = main(["identify", str(bag), "--json", str(out), "--format", "none", *extra])
    return code, json.loads(out.read_text())


def test_a_cocontraction_the_torque_cannot_show_is_left_out_and_named(tmp_path: Path) -> None:
    """A relaxed arm but for 4 s of biceps and triceps together (no net torque): with its EMG the stretch is left
    out and named (EMG alone), the estimate valid and within 3 std; without it nothing is named."""
    arm = draw_arm(5)
    options = CellOptions(trajectory=paper_sine(0.03), duration_s=40.0, wrench_hz=250.0, seed=5)
    session = patient_session(arm, options, Patient(emg=EmgRecording(cocontraction_s=4.0)))
    bag = write_bag(tmp_path / "cocontraction", session.cell)
    truth = json.loads((bag / "truth.json").read_text())

    code, estimate = _identify(bag, tmp_path / "with_emg.json")
    assert code == 0, estimate["quality"]["message"]
    active = [f for f in estimate["quality"]["findings"] if f["code"] == "arm_active"]
    assert len(active) == 1, estimate["quality"]["findings"]
    values = active[0]["values"]
    assert values["torque_share_percent"] == 0.0 and active[0]["where"] == ""
    assert values["channels"] == "biceps, triceps"
    # the stretch: 4 s, widened by 0.1 s before and 0.3 s after, its ramps partly under the threshold
    assert 3.6 < values["active_s"] < 4.6
    assert values["emg_only_percent"] == pytest.approx(values["active_percent"], abs=0.5)
    for segment, quantities in estimate["segments"].items():
        q, true = quantities["static_moment_kgm"], truth["segments"][segment]["static_moment_kgm"]
        assert abs(q["value"] - true) < 3.0 * q["std"], segment

    code, without = _identify(bag, tmp_path / "without_emg.json", "--emg-topic", "")
    assert code == 0
    assert "arm_active" not in [f["code"] for f in without["quality"]["findings"]]
    rows = estimate["diagnostics"]["rows_used"]["elbow"], without["diagnostics"]["rows_used"]["elbow"]
    assert rows[0] < rows[1] * (1.0 - 0.8 * values["active_percent"] / 100.0)
