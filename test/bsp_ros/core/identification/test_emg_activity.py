"""The EMG rule (baseline + 3 sd over 100 ms) on envelopes made as an amplifier makes them: white noise (and, in a
burst, muscle activity) rectified and low-passed at 6 Hz, sampled at 100 Hz; and the checks on a bad stream."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import butter, sosfilt

from bsp_ros.core.emg import EmgProblem, check_emg, combined_emg
from bsp_ros.core.findings import Finding, FindingCode
from bsp_ros.core.identification.joint.emg_activity import EmgSettings, emg_activity, emg_values
from bsp_ros.core.streams import EmgSeries

RAW_HZ = 2000
RATE_HZ = 100
T0_NS = 1_700_000_000_000_000_000
CHANNELS = ("biceps", "triceps", "deltoid_anterior")


def envelopes(
    rng: np.random.Generator, duration_s: float, bursts: dict[int, list[tuple[float, float, float]]], floor_uv: float
) -> EmgSeries:
    """Envelopes of the three channels, uV: a noise floor of ``floor_uv`` RMS, and in each channel's bursts
    ``(start_s, end_s, gain)`` muscle activity of ``gain`` times that floor, rectified and low-passed at 6 Hz."""
    n = int(duration_s * RAW_HZ)
    t_s = np.arange(n) / RAW_HZ
    sos = butter(2, 6.0, fs=RAW_HZ, output="sos")
    columns = []
    for c in range(len(CHANNELS)):
        drive = np.zeros(n)
        for start, end, gain in bursts.get(c, []):
            drive[(t_s >= start) & (t_s < end)] = gain
        raw = floor_uv * rng.standard_normal(n) * np.sqrt(1.0 + drive**2)
        columns.append(sosfilt(sos, np.abs(raw))[:: RAW_HZ // RATE_HZ])
    t_ns = T0_NS + np.arange(columns[0].size, dtype=np.int64) * (1_000_000_000 // RATE_HZ)
    return EmgSeries(t_ns=t_ns, envelope=np.column_stack(columns), channels=CHANNELS)


BURSTS = {0: [(20.0, 21.5, 3.0), (61.0, 64.0, 2.0)], 1: [(61.5, 63.0, 4.0)], 2: [(95.0, 95.6, 3.0)]}


def _spans_s(spans_ns: tuple[tuple[int, int], ...]) -> list[tuple[float, float]]:
    return [((a - T0_NS) * 1e-9, (b - T0_NS) * 1e-9) for a, b in spans_ns]


def test_finds_the_bursts_and_nothing_else() -> None:
    series = envelopes(np.random.default_rng(1), 120.0, BURSTS, floor_uv=3.0)
    settings = EmgSettings()
    activity = emg_activity(series, settings)
    spans = _spans_s(activity.spans_ns)
    truth = sorted({(a, b) for runs in BURSTS.values() for a, b, _ in runs})
    assert activity.fired == CHANNELS
    # each burst (channels 0 and 1 overlap at 61-64 s) is one stretch, onset and end within the filter's smear
    assert len(spans) == 3, spans
    for (start, end), (true_start, true_end) in zip(spans, [truth[0], (61.0, 64.0), truth[-1]], strict=True):
        assert true_start - settings.lead_s - 0.15 <= start <= true_start - settings.lead_s + 0.1
        assert true_end + settings.lag_s - 0.1 <= end <= true_end + settings.lag_s + 0.2
    # the baseline is the floor's: a rectified Gaussian of 3 uV RMS has mean 3 sqrt(2/pi) = 2.39 uV
    np.testing.assert_allclose(activity.baseline, 2.39, rtol=0.05)
    inside = activity.active_at(series.t_ns)
    t_s = (series.t_ns - T0_NS) * 1e-9
    assert not inside[(t_s > 30) & (t_s < 55)].any()
    assert inside[(t_s > 20.2) & (t_s < 21.3)].all()


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_no_false_alarm_on_a_quiet_floor(seed: int) -> None:
    series = envelopes(np.random.default_rng(seed), 300.0, {}, floor_uv=2.0 + seed)
    activity = emg_activity(series)
    assert activity.spans_ns == ()
    assert activity.fired == ()
    assert not activity.active_at(series.t_ns).any()


def test_the_rule_is_scale_free() -> None:
    series = envelopes(np.random.default_rng(5), 120.0, BURSTS, floor_uv=3.0)
    in_volts = EmgSeries(t_ns=series.t_ns, envelope=series.envelope * 1e-6, channels=CHANNELS)
    assert emg_activity(in_volts).spans_ns == emg_activity(series).spans_ns


def test_only_stretches_of_100_ms_count() -> None:
    """On a quiet floor, 5 sd above the baseline for 30 ms (a twitch, an electrode's pop) is noise; for 200 ms it
    is activity."""
    quiet = envelopes(np.random.default_rng(2), 60.0, {}, floor_uv=3.0)
    activity = emg_activity(quiet)
    assert activity.spans_ns == ()
    envelope = quiet.envelope.copy()
    envelope[3000:3003, 0] = activity.baseline[0] + 5.0 * activity.sd[0]
    short = EmgSeries(t_ns=quiet.t_ns, envelope=envelope, channels=CHANNELS)
    assert emg_activity(short).spans_ns == ()
    envelope[4000:4020, 1] = activity.baseline[1] + 5.0 * activity.sd[1]
    spans = _spans_s(emg_activity(EmgSeries(t_ns=quiet.t_ns, envelope=envelope, channels=CHANNELS)).spans_ns)
    assert len(spans) == 1 and spans[0][0] < 40.0 < 40.2 < spans[0][1]


def test_values_of_the_finding() -> None:
    series = envelopes(np.random.default_rng(1), 120.0, BURSTS, floor_uv=3.0)
    activity = emg_activity(series)
    t_ns = series.t_ns[::4]
    emg_active = activity.active_at(t_ns)
    torque_active = np.zeros(t_ns.size, dtype=bool)
    torque_active[: t_ns.size // 10] = True  # the first 12 s: no EMG there
    values = emg_values(torque_active, emg_active, activity)
    assert values["confirmed_percent"] == 0.0
    assert values["torque_share_percent"] == pytest.approx(10.0, abs=0.1)
    assert values["emg_only_percent"] == pytest.approx(values["emg_share_percent"])
    assert values["channels"] == "biceps, triceps, deltoid_anterior"
    finding = Finding(
        code=FindingCode.ARM_ACTIVE,
        where="elbow",
        values={"n_stretches": 4, "active_s": 20.0, "active_percent": 16.7, "peak_nm": 0.5, **values},
    )
    assert "EMG above its quiet baseline + 3 sd" in finding.text and "co-contraction" in finding.text


def _series(n: int = 3000, rate_hz: float = RATE_HZ, **kwargs: object) -> EmgSeries:
    rng = np.random.default_rng(0)
    t_ns = T0_NS + (np.arange(n) * (1e9 / rate_hz)).astype(np.int64)
    return EmgSeries(t_ns=t_ns, envelope=3.0 + rng.random((n, 3)), channels=CHANNELS, **kwargs)  # type: ignore[arg-type]


def _problem(series: EmgSeries) -> str | None:
    check = check_emg(series)
    assert (check.series is None) == (check.finding is not None)
    if check.finding is None:
        return None
    assert check.finding.code is FindingCode.EMG_UNUSABLE
    assert "not used" in check.finding.text
    return str(check.finding.values["problem"])


def test_a_bad_stream_is_one_finding_naming_why() -> None:
    good = _series()
    assert _problem(good) is None
    nan = good.envelope.copy()
    nan[::10, 1] = np.nan  # 10 %: a lead off
    assert _problem(EmgSeries(t_ns=good.t_ns, envelope=nan, channels=CHANNELS)) == EmgProblem.NON_FINITE
    negative = good.envelope - 3.5  # raw, not an envelope
    assert _problem(EmgSeries(t_ns=good.t_ns, envelope=negative, channels=CHANNELS)) == EmgProblem.NEGATIVE
    assert _problem(_series(other_layout=12)) == EmgProblem.CHANNELS_CHANGE
    assert _problem(_series(n=1500)) == EmgProblem.TOO_SHORT
    assert _problem(_series(n=300, rate_hz=10.0)) == EmgProblem.TOO_SLOW
    assert _problem(EmgSeries(t_ns=good.t_ns, envelope=np.zeros((good.t_ns.size, 0)), channels=())) == (
        EmgProblem.NO_CHANNELS
    )


def test_a_few_bad_samples_are_left_out() -> None:
    good = _series()
    few = good.envelope.copy()
    few[::50, 0] = np.nan
    few[7, 2] = -1.0
    t_ns = good.t_ns.copy()
    t_ns[98] = t_ns[97]  # a repeated stamp
    check = check_emg(EmgSeries(t_ns=t_ns, envelope=few, channels=CHANNELS))
    assert check.series is not None and check.finding is None
    assert check.dropped == 60 + 1 + 1
    assert np.isfinite(check.series.envelope).all() and (check.series.envelope >= 0).all()


def test_recordings_combine_only_with_the_same_channels() -> None:
    first = _series()
    second = EmgSeries(t_ns=first.t_ns + 10**12, envelope=first.envelope, channels=CHANNELS)
    both = combined_emg([second, first])
    assert both is not None and both.t_ns.size == 2 * first.t_ns.size and bool((np.diff(both.t_ns) > 0).all())
    assert combined_emg([first, None]) is None
    assert combined_emg([first, EmgSeries(t_ns=second.t_ns, envelope=first.envelope, channels=("a", "b", "c"))]) is None
