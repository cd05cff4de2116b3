"""`bsp identify` on bags with EMG envelopes: a bad stream is one finding and changes nothing else; a quiet one
changes nothing at all; a burst of EMG alone is left out."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from bsp_ros.bag import write_session_bag
from bsp_ros.cli import main
from bsp_ros.core.simulation import SimulatedSession, human_arm_cell, simulate_cell
from bsp_ros.core.streams import EmgSeries

CHANNELS = ("biceps", "triceps", "deltoid_anterior")


@pytest.fixture(scope="module")
def simulated() -> SimulatedSession:
    return simulate_cell(human_arm_cell(duration_s=60.0, seed=11))


def _quiet_emg(simulated: SimulatedSession, seed: int = 2) -> EmgSeries:
    """100 Hz envelopes over the session: a smooth floor (its sd a few percent of its mean) of about 3 uV."""
    t_w = simulated.session.wrench.t_ns
    t_ns = np.arange(t_w[0], t_w[-1], 10_000_000, dtype=np.int64)
    rng = np.random.default_rng(seed)
    kernel = np.hanning(15) / np.hanning(15).sum()  # about 6 Hz
    noise = np.column_stack([np.convolve(rng.standard_normal(t_ns.size), kernel, "same") for _ in CHANNELS])
    return EmgSeries(t_ns=t_ns, envelope=2.4 + 0.3 * noise, channels=CHANNELS)


def _identify(simulated: SimulatedSession, emg: EmgSeries | None, tmp_path: Path, name: str) -> tuple[int, dict]:
    session = dataclasses.replace(simulated.session, emg=emg)
    bag = write_session_bag(tmp_path / name, session, simulated.truth.to_dict())
    out = tmp_path / f"{name}.json"
    code = main(["identify", str(bag), "--json", str(out), "--format", "none"])
    return code, json.loads(out.read_text())


def _without_emg_keys(document: dict) -> dict:
    """The estimate but for what differs by the bag's content and name alone (its hash, its EMG messages, names)."""
    out = json.loads(json.dumps(document))
    out["session"].pop("content_sha256", None)
    out["session"].pop("source", None)
    out["bag"]["messages"].pop("/emg/envelope", None)
    out["bag"].pop("files")
    return out


def test_a_bad_stream_is_one_note_and_changes_nothing_else(simulated: SimulatedSession, tmp_path: Path) -> None:
    code, plain = _identify(simulated, None, tmp_path, "plain")
    assert code == 0, plain["quality"]["message"]
    emg = _quiet_emg(simulated)
    lead_off = emg.envelope.copy()
    lead_off[::8, 2] = np.nan  # 12.5 %: a lead off
    code, bad = _identify(simulated, dataclasses.replace(emg, envelope=lead_off), tmp_path, "bad")
    assert code == 0
    notes = [f for f in bad["quality"]["findings"] if f["code"] == "emg_unusable"]
    assert len(notes) == 1 and notes[0]["values"]["problem"] == "non_finite", bad["quality"]["findings"]
    assert notes[0]["severity"] == "note"
    bad["quality"]["findings"].remove(notes[0])
    bad["quality"]["warnings"].remove(notes[0]["text"])
    assert _without_emg_keys(bad) == _without_emg_keys(plain)


def test_a_quiet_stream_changes_nothing(simulated: SimulatedSession, tmp_path: Path) -> None:
    _, plain = _identify(simulated, None, tmp_path, "plain")
    _, quiet = _identify(simulated, _quiet_emg(simulated), tmp_path, "quiet")
    assert _without_emg_keys(quiet) == _without_emg_keys(plain)


def test_emg_alone_is_left_out(simulated: SimulatedSession, tmp_path: Path) -> None:
    """Biceps at four times its floor for 3 s, the arm's torque relaxed throughout: the stretch is left out."""
    emg = _quiet_emg(simulated)
    t_s = (emg.t_ns - emg.t_ns[0]) * 1e-9
    busy = emg.envelope.copy()
    busy[(t_s > 30.0) & (t_s < 33.0), 0] *= 4.0
    code, estimate = _identify(simulated, dataclasses.replace(emg, envelope=busy), tmp_path, "busy")
    assert code == 0
    (active,) = [f for f in estimate["quality"]["findings"] if f["code"] == "arm_active"]
    assert active["values"]["channels"] == "biceps" and active["values"]["torque_share_percent"] == 0.0
    assert active["values"]["active_s"] == pytest.approx(3.0 + 0.1 + 0.3, abs=0.1)
