"""EMG envelopes in the live window: a co-contraction the torque cannot show is left out of the window's identification
as `bsp identify` leaves it out, at the model checks' update and at the refits between them; the buffer judges
nothing itself, and the node's receipt stamps land on the wrench's clock."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from live_inputs import WindowFeed

from bsp_ros.core.findings import FindingCode, findings_of
from bsp_ros.core.streams import EmgSeries
from bsp_ros.live.online.emg_buffer import EmgBuffer
from bsp_ros.live.online.identifier_settings import IdentifierSettings
from bsp_ros.live.online.live_identifier import LiveIdentifier
from bsp_ros.live.online.windowed import WindowConfig, WindowedIdentifier, WindowSamples
from msg_adapters.wrench import WrenchSample

CHANNELS = ("biceps", "triceps", "deltoid_anterior")
BURST_S = (15.0, 18.0)  # seconds before the first window's end: biceps at four times its floor
LEAD_S, LAG_S = 0.1, 0.3  # the rule's widening (EmgSettings)


def _envelopes(t0_ns: int, t1_ns: int, burst_ns: tuple[int, int] | None, seed: int = 2) -> EmgSeries:
    """100 Hz envelopes over ``t0_ns .. t1_ns``: a smooth floor of about 2.4 uV (its sd a few percent of its mean),
    and where ``burst_ns`` is given the biceps at four times it there (a co-contraction: no net torque)."""
    t_ns = np.arange(t0_ns, t1_ns, 10_000_000, dtype=np.int64)
    rng = np.random.default_rng(seed)
    kernel = np.hanning(15) / np.hanning(15).sum()  # about 6 Hz
    noise = np.column_stack([np.convolve(rng.standard_normal(t_ns.size), kernel, "same") for _ in CHANNELS])
    envelope = 2.4 + 0.3 * noise
    if burst_ns is not None:
        envelope[(t_ns >= burst_ns[0]) & (t_ns < burst_ns[1]), 0] *= 4.0
    return EmgSeries(t_ns=t_ns, envelope=envelope, channels=CHANNELS)


class _Feed(WindowFeed):
    """:class:`WindowFeed` with the EMG rows too, each at its stamp."""

    def __init__(self, identifier: WindowedIdentifier, streams: Any, emg: EmgSeries | None) -> None:
        _, stamps, wrench, _, raw = streams
        super().__init__(identifier, stamps, wrench, raw)
        self.emg, self._emg_i = emg, 0

    def until(self, t_ns: int) -> None:
        super().until(t_ns)
        emg = self.emg
        while emg is not None and self._emg_i < emg.t_ns.size and emg.t_ns[self._emg_i] <= t_ns:
            self.identifier.add_emg(int(emg.t_ns[self._emg_i]), CHANNELS, emg.envelope[self._emg_i])
            self._emg_i += 1


def _fed(streams: Any, with_burst: bool | None, end_ns: int) -> WindowedIdentifier:
    """A 30 s window fed up to ``end_ns``: with EMG (a burst or not), or without (``with_burst`` None)."""
    _, stamps, *_ = streams
    burst = (end_ns - int(BURST_S[1] * 1e9), end_ns - int(BURST_S[0] * 1e9))
    emg = None if with_burst is None else _envelopes(int(stamps[0]), int(stamps[-1]), burst if with_burst else None)
    identifier = WindowedIdentifier(3, WindowConfig(window_s=30.0))
    feed = _Feed(identifier, streams, emg)
    feed.until(end_ns)
    identifier.feed = feed  # type: ignore[attr-defined]  # to feed it on
    return identifier


def _activity(document: dict) -> list:
    return [f for f in findings_of(document["quality"]) if f.code is FindingCode.ARM_ACTIVE]


def _rows(document: dict) -> np.ndarray:
    return np.array(list(document["diagnostics"]["rows_used"].values()))


def _left_out_truth(identifier: WindowedIdentifier, end_ns: int) -> int:
    """The window's identification samples inside the burst widened by the rule (the truth the test set)."""
    window = identifier.snapshot()
    assert isinstance(window, WindowSamples)
    data, _ = identifier.estimator._window_data(window)
    assert not isinstance(data, str)
    start = end_ns - int((BURST_S[1] + LEAD_S) * 1e9)
    stop = end_ns - int((BURST_S[0] - LAG_S) * 1e9)
    return int(((data.t_ns >= start) & (data.t_ns <= stop)).sum())


def test_a_cocontraction_is_left_out_at_the_check_and_at_the_refits_between(live_streams: Any) -> None:
    """The burst's 3.4 s (3 s widened by 0.1 s before and 0.3 s after) are left out of every joint's rows, named by
    the biceps with no torque share; the refits between checks leave the burst out too and say so once; the
    estimate stays within a third of its std of the one without EMG (a co-contraction moves no torque) and holds
    the truth. A quiet EMG stream changes nothing."""
    simulated, stamps, *_ = live_streams
    end_ns = int(stamps[-1]) - 2_000_000_000
    busy, quiet, plain = (_fed(live_streams, b, end_ns) for b in (True, False, None))
    left_out = _left_out_truth(plain, end_ns)
    assert 165 <= left_out <= 175  # 3.4 s at the window's 50 Hz
    truth = simulated.truth.to_dict()["segments"]
    for update in range(3):  # the checks' update, then two refits of what they chose, 0.2 s more samples each
        if update:
            for identifier in (busy, quiet, plain):
                identifier.feed.until(end_ns + update * 200_000_000)  # type: ignore[attr-defined]
        estimates = [identifier.estimate().document for identifier in (busy, quiet, plain)]
        assert all(d["quality"]["valid"] for d in estimates), [d["quality"]["message"] for d in estimates]
        with_burst, without_burst, without_emg = estimates
        assert without_burst == without_emg
        (active,) = _activity(with_burst)
        assert active.values["channels"] == "biceps" and active.values["torque_share_percent"] == 0.0
        assert active.values["active_s"] == pytest.approx(3.0 + LEAD_S + LAG_S, abs=0.1), update
        assert not _activity(without_emg)
        dropped = _rows(without_emg) - _rows(with_burst)
        # Each joint loses at most the burst's samples (within the envelope's smear); the shoulder and elbow, whose
        # rows there were all in use, lose them all (the slow wrist's rows about its turns were out already).
        assert (dropped <= 1.05 * left_out).all() and (dropped[:2] >= 0.95 * left_out).all(), (update, dropped)
        for segment, q in with_burst["segments"].items():
            value, std = q["static_moment_kgm"]["value"], q["static_moment_kgm"]["std"]
            assert abs(value - without_emg["segments"][segment]["static_moment_kgm"]["value"]) < std / 3, segment
            assert abs(value - truth[segment]["static_moment_kgm"]) < 3.0 * std, segment
    assert busy.estimator._since_check == 3  # the last two were refits of the held model


def test_the_buffer_keeps_bad_rows_for_the_rule_and_a_change_of_channels_spoils_its_windows() -> None:
    t0 = 1_700_000_000_000_000_000
    buffer = EmgBuffer(horizon_ns=35_000_000_000)
    assert buffer.series(t0) is None  # no envelope ever came: no EMG, not an empty one
    assert buffer.add(t0, CHANNELS, np.array([1.0, np.nan, -2.0]))  # the rule judges these, not the buffer
    assert not buffer.add(t0, CHANNELS, np.ones(3)) and buffer.out_of_order == 1
    assert buffer.add(t0 + 10_000_000, ("biceps", "triceps"), np.ones(2))  # another layout: a fresh start
    series = buffer.series(t0)
    assert series is not None and series.channels == ("biceps", "triceps") and series.other_layout == 1
    assert series.t_ns.tolist() == [t0 + 10_000_000]
    later = buffer.series(t0 + 1)
    assert later is not None and later.other_layout == 0  # a window after the change holds no earlier channels
    assert buffer.add(t0 + 20_000_000, ("a,b",), np.ones(3))  # a label that names not every value
    assert buffer.channels == ("channel_0", "channel_1", "channel_2")
    assert buffer.add(t0 - 5_000_000_000, CHANNELS, np.ones(3))  # 5 s back: a clock jump starts afresh
    series = buffer.series(0)
    assert series is not None and series.t_ns.tolist() == [t0 - 5_000_000_000] and series.other_layout == 0


def test_a_window_whose_channels_changed_does_not_use_its_emg(live_streams: Any) -> None:
    """Like a bag whose EMG channels change: the window names why (``emg_unusable``, channels_change) and finds no
    activity from it."""
    _, stamps, *_ = live_streams
    end_ns = int(stamps[-1]) - 2_000_000_000
    identifier = _fed(live_streams, None, end_ns)
    change_ns = end_ns - 10_000_000_000
    emg = _envelopes(end_ns - 40_000_000_000, end_ns, (change_ns - 5_000_000_000, change_ns - 2_000_000_000))
    for t_ns, row in zip(emg.t_ns.tolist(), emg.envelope, strict=True):
        identifier.add_emg(t_ns, CHANNELS if t_ns < change_ns else ("biceps", "triceps", "deltoid"), row)
    document = identifier.estimate().document
    unusable = [f for f in findings_of(document["quality"]) if f.code is FindingCode.EMG_UNUSABLE]
    assert [f.values["problem"] for f in unusable] == ["channels_change"], document["quality"]["warnings"]
    assert not _activity(document)


@pytest.mark.parametrize("mode", ["windowed", "recursive"])
def test_the_node_s_receipt_stamps_land_on_the_wrench_clock(mode: str) -> None:
    """Before any wrench an envelope cannot be placed (dropped, counted); after one stamped 10 s before its receipt
    (a bag played without /clock), an envelope received 5 ms later is stamped 5 ms after that wrench's stamp, in
    the window of either mode (the recursive mode's window checks read it)."""
    identifier = LiveIdentifier(IdentifierSettings.from_parameters({"mode": mode}), lambda e: e, pytest.fail)
    now = 1_700_000_000_000_000_000
    identifier.add_emg(CHANNELS, np.ones(3), now)
    assert identifier.counters()["emg_before_wrench"] == 1
    stamp = now - 10_000_000_000
    identifier.wrench_received(stamp, now)
    identifier.add_wrench(WrenchSample(stamp, "ft_sensor", np.zeros(3), np.zeros(3)), np.eye(3))
    identifier.add_emg(CHANNELS, np.full(3, 2.0), now + 5_000_000)
    identifier.add_emg(CHANNELS, np.full(3, 2.0), now + 5_000_000)  # the same receipt again: refused
    series = identifier.mode.window.emg.series(0)
    assert series is not None and series.t_ns.tolist() == [stamp + 5_000_000]
    assert identifier.counters()["emg"] == 1 and identifier.counters()["refused"] == 1
