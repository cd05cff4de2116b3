"""Benchmark: latency, update rate, CPU, memory and loss of the live node suite on rclpy + Fast DDS at 1 kHz."""

from __future__ import annotations

import argparse
import json
import os
import signal
import struct
import subprocess
import sys
import threading
import time
from array import array
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from finding_kinds import cause_of

from bsp_ros.live.runtime.ros import EXECUTOR_ENV, Client, has_message
from msg_adapters.diagnostics import read_diagnostic_array
from msg_adapters.stamps import stamp_to_ns

WRENCH_HZ, MARKER_HZ, SPEED = 1000.0, 100.0, 1.0
PERIOD_NS = int(1e9 / WRENCH_HZ)  # the simulator's wrench grid: stamp = start + k * PERIOD_NS
UPDATE_HZ = 5.0  # the identifier's default estimate rate
TICK_MS = 1.0  # the simulator publishes every due sample on a 1 ms timer (its default tick_s)
NODES = ("joint_angle_estimator", "bsp_identifier", "cell_simulator")
RECEIVED_KEYS = ("wrench", "refused", "waiting_for_tf")  # every wrench the identifier took off the wire
CLK_TCK = os.sysconf("SC_CLK_TCK")
PAGE = os.sysconf("SC_PAGE_SIZE")
RECURSIVE_P99_MS = 5.0
# "Flat memory": RSS growth per node over the second half of the measured run below this, along the line fitted
# through its samples (half_trend_mb). The windowed identifier's 30 s window is still filling after a 20 s
# warm-up, so growth from the start is expected.
FLAT_MB = 1.0


def _cpu_s(stat_path: str) -> tuple[float, float]:
    with open(stat_path) as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return int(fields[11]) / CLK_TCK, int(fields[12]) / CLK_TCK


def half_trend_mb(series_mb: np.ndarray) -> float:
    """The growth over the samples ``series_mb`` (RSS, MB, evenly spaced) of the least-squares line through them.

    The last sample minus the first swings by 1-2 MB either way as glibc returns freed pages and takes them again
    (an identifier at 114.3-115.6 MB for nine minutes, then 112.6: bench/README.md, twentieth session); a leak is
    the slope every sample shares."""
    if series_mb.size < 2:
        return 0.0
    steps = np.arange(series_mb.size, dtype=np.float64)
    slope = np.polyfit(steps, series_mb, 1)[0]
    return float(slope * (series_mb.size - 1))


def proc_cpu_rss(pid: int) -> tuple[float, float, float, float]:
    """User, system and main-thread CPU seconds and resident set size in MB of a process, from /proc."""
    user, system = _cpu_s(f"/proc/{pid}/stat")
    main_thread = sum(_cpu_s(f"/proc/{pid}/task/{pid}/stat"))
    with open(f"/proc/{pid}/statm") as f:
        rss_pages = int(f.read().split()[1])
    return user, system, main_thread, rss_pages * PAGE / 2**20


def machine_busy() -> tuple[float, float, float]:
    """Busy, total and stolen (by the hypervisor) CPU seconds of the whole machine, from /proc/stat."""
    with open("/proc/stat") as f:
        ticks = [int(v) for v in f.readline().split()[1:]]
    idle = ticks[3] + ticks[4]
    return (sum(ticks[:7]) - idle) / CLK_TCK, sum(ticks[:8]) / CLK_TCK, ticks[7] / CLK_TCK


def pct(values: np.ndarray, q: float) -> float:
    return float(np.percentile(values, q)) if values.size else float("nan")


def stats_ms(values_ns: np.ndarray) -> str:
    v = values_ns / 1e6
    if not v.size:
        return "no samples"
    return f"p50 {pct(v, 50):8.3f}  p99 {pct(v, 99):8.3f}  max {float(v.max()):8.3f} ms  (n={v.size})"


@dataclass
class Snapshot:
    """Resources of every node (and of this listener and the machine) at one instant."""

    wall_ns: int
    cpu_s: dict[str, tuple[float, float, float]]  # user, system, main thread
    rss_mb: dict[str, float]
    machine: tuple[float, float, float]


@dataclass
class Stream:
    """Stamps, publication times (the middleware's source timestamps) and listener receive times of one topic."""

    stamp: array = field(default_factory=lambda: array("q"))
    pub: array = field(default_factory=lambda: array("q"))
    recv: array = field(default_factory=lambda: array("q"))

    def add(self, stamp_ns: int, info: dict[str, int] | None) -> None:
        self.recv.append(time.time_ns())
        self.stamp.append(stamp_ns)
        self.pub.append(int(info["source_timestamp"]) if info else -1)

    def arrays(self, lo_ns: int, hi_ns: int, by: str = "recv") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(stamp, pub, recv) of the messages whose ``by`` time ("recv" or "stamp") is in [lo_ns, hi_ns)."""
        stamp, pub, recv = (np.frombuffer(a, dtype=np.int64) for a in (self.stamp, self.pub, self.recv))
        key = recv if by == "recv" else stamp
        keep = (key >= lo_ns) & (key < hi_ns)
        return stamp[keep], pub[keep], recv[keep]


class RawStamps(threading.Thread):
    """Receive times, header stamps and source timestamps of 1 kHz topics, taken raw on a thread of its own.

    A private rclpy context with raw subscriptions: decoding only the header stamp (CDR offset 4: int32 sec,
    uint32 nanosec) keeps the listener from loading the 2 cores the nodes share.
    """

    def __init__(self, domain: int, topics: dict[str, tuple[str, str, Stream]]) -> None:
        super().__init__(name="bench-raw-stamps", daemon=True)
        from rclpy.qos import HistoryPolicy, QoSProfile, ReliabilityPolicy

        from bsp_ros.live.runtime.qos import qos_spec

        self.client = Client("bench_raw_listener", domain)
        for topic, (type_name, profile, stream) in topics.items():
            reliable = qos_spec(profile).reliable
            qos = QoSProfile(
                history=HistoryPolicy.KEEP_LAST,
                depth=5000,
                reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
            )

            def on_raw(data: bytes, info: dict[str, int], stream: Stream = stream) -> None:
                sec, nanosec = struct.unpack_from("<iI", data, 4)
                stream.add(sec * 1_000_000_000 + nanosec, info)

            # rclpy hands a callback of two parameters the message's info too (its stubs name one parameter only).
            callback: Any = on_raw
            self.client.node.create_subscription(self.client_message(type_name), topic, callback, qos, raw=True)
        self.stop = threading.Event()

    @staticmethod
    def client_message(type_name: str) -> Any:
        from bsp_ros.live.runtime.ros import message_class

        return message_class(type_name)

    def run(self) -> None:
        while not self.stop.is_set():
            self.client.spin(0.1)
        self.client.close()


def invalid_cause(estimate_json: str) -> str | None:
    """Why the estimate ``estimate_json`` (as ``bsp/estimate_json`` carries it) is invalid: its first invalid
    finding's code and where (``bench/finding_kinds.py``); None for a valid one."""
    quality = json.loads(estimate_json).get("quality", {})
    return None if quality.get("valid") else cause_of(quality)


class Listener:
    """In-process rclpy listener: wrench, estimates, passive moments, diagnostics and the simulator's start."""

    def __init__(self, domain: int) -> None:
        self.client = Client("bench_listener", domain)
        self.wrench, self.estimate, self.passive = Stream(), Stream(), Stream()
        self.raw = RawStamps(
            domain,
            {
                "/ft_sensor/wrench": ("geometry_msgs/msg/WrenchStamped", "sensor_data", self.wrench),
                "/bsp/passive_moments": ("sensor_msgs/msg/JointState", "estimates", self.passive),
            },
        )
        self.raw.start()
        self.estimate_valid = array("b")
        self.invalid_reasons: dict[str, int] = {}
        self.diagnostics: dict[str, list[tuple[int, int, dict[str, str]]]] = {}
        self.start_ns: int | None = None
        # With the message's info, as RawStamps' callbacks (rclpy's stubs name one parameter only).
        on_estimate: Any = self._on_estimate
        self.client.subscribe("diagnostic_msgs/msg/DiagnosticArray", "bsp/estimate", on_estimate, "estimates")
        self.client.subscribe("std_msgs/msg/String", "bsp/estimate_json", self._on_estimate_json, "estimates")
        self.client.subscribe("diagnostic_msgs/msg/DiagnosticArray", "/diagnostics", self._on_diag, "default")
        self.client.subscribe("std_msgs/msg/String", "sim/truth", self._on_truth, "tf_static_listener")

    def _on_estimate(self, msg: Any, info: dict[str, int]) -> None:
        self.estimate.add(stamp_to_ns(msg.header.stamp), info)
        quality = [s for s in msg.status if s.name.endswith("/quality")]
        valid = any(kv.key == "valid" and kv.value == "True" for s in quality for kv in s.values)
        self.estimate_valid.append(int(valid))

    def _on_estimate_json(self, msg: Any) -> None:
        cause = None if self.start_ns is None else invalid_cause(msg.data)
        if cause is not None:
            self.invalid_reasons[cause] = self.invalid_reasons.get(cause, 0) + 1

    def _on_diag(self, msg: Any) -> None:
        sample = read_diagnostic_array(msg)
        for status in sample.status:
            self.diagnostics.setdefault(status.name, []).append((time.time_ns(), sample.t_ns, dict(status.values)))

    def _on_truth(self, msg: Any) -> None:
        if self.start_ns is None:
            self.start_ns = int(json.loads(msg.data)["start_time_ns"])  # the simulator's start wall time

    def spin_until(self, wall_ns: int) -> None:
        while time.time_ns() < wall_ns:
            self.client.spin(min(0.2, max(0.001, (wall_ns - time.time_ns()) / 1e9)))


def _wrench_frame_parameter() -> list[str]:
    """The simulated sensor's rotation for the identifier where /tf_static cannot carry it (no tf2_msgs)."""
    if has_message("tf2_msgs/msg/TFMessage"):
        return []
    from bsp_ros.core.simulation import human_arm_cell
    from msg_adapters.rotation import quaternion_from_matrix

    xyzw = quaternion_from_matrix(human_arm_cell().sensor.rotation_world_from_sensor)
    return ["wrench_frame_rotation_xyzw:=[" + ", ".join(repr(float(v)) for v in xyzw) + "]"]


class Cell:
    """The three nodes as processes on one private domain."""

    def __init__(self, domain: int, log_dir: str | None, executor: str) -> None:
        self.env = {**os.environ, "ROS_DOMAIN_ID": str(domain), EXECUTOR_ENV: executor}
        self.log_dir = log_dir
        self.processes: dict[str, subprocess.Popen[bytes]] = {}

    def start(self, name: str, params: list[str], script: str | None = None) -> None:
        """Start node ``name`` (``python -m bsp_ros.live.nodes.<name>``, or the file ``script`` in its place)."""
        args = ["--ros-args", *[a for p in params for a in ("-p", p)]] if params else []
        out = open(os.path.join(self.log_dir, f"{name}.log"), "wb") if self.log_dir else subprocess.DEVNULL
        program = [script] if script else ["-m", f"bsp_ros.live.nodes.{name}"]
        self.processes[name] = subprocess.Popen([sys.executable, *program, *args], env=self.env, stdout=out, stderr=out)

    def alive(self) -> dict[str, bool]:
        return {name: p.poll() is None for name, p in self.processes.items()}

    def close(self) -> None:
        for process in self.processes.values():
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
        for process in self.processes.values():
            try:
                process.wait(10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(5)


def snapshot(cell: Cell) -> Snapshot:
    cpu, rss = {}, {}
    for name, process in [*cell.processes.items(), ("listener", None)]:
        try:
            user, system, main_thread, rss[name] = proc_cpu_rss(process.pid if process is not None else os.getpid())
            cpu[name] = (user, system, main_thread)
        except (OSError, IndexError):
            cpu[name], rss[name] = (float("nan"),) * 3, float("nan")
    return Snapshot(time.time_ns(), cpu, rss, machine_busy())


def identifier_counts(listener: Listener, before_ns: int | None = None) -> tuple[int, dict[str, int]] | None:
    """(stamp, counters) of the identifier's newest /diagnostics status stamped before ``before_ns``."""
    rows = [r for r in listener.diagnostics.get("bsp_identifier", []) if before_ns is None or r[1] <= before_ns]
    if not rows:
        return None
    _, stamp, values = rows[-1]
    return stamp, {k: int(v) for k, v in values.items() if v.lstrip("-").isdigit()}


def received(counts: dict[str, int]) -> int:
    return sum(counts.get(k, 0) for k in RECEIVED_KEYS)


def run_mode(
    mode: str, executor: str, domain: int, duration_s: float, warmup_s: float, log_dir: str | None
) -> dict[str, Any]:
    """Run the cell in one identifier mode, its nodes on one rclpy executor, and return what was measured."""
    listener = Listener(domain)
    cell = Cell(domain, log_dir, executor)
    result: dict[str, Any] = {"mode": mode, "executor": executor, "domain": domain}
    try:
        cell.start("joint_angle_estimator", [f"marker_hz:={MARKER_HZ}"])
        if mode == "relay":  # the floor: a node that only relays each wrench's stamp (bench/relay_node.py)
            cell.start("bsp_identifier", [], os.path.join(os.path.dirname(os.path.abspath(__file__)), "relay_node.py"))
        else:
            cell.start("bsp_identifier", [f"mode:={mode}", f"update_hz:={UPDATE_HZ}", *_wrench_frame_parameter()])
        deadline = time.time_ns() + int(60e9)
        while not {"bsp_identifier", "joint_angle_estimator"} <= listener.diagnostics.keys():
            if time.time_ns() > deadline or not all(cell.alive().values()):
                raise RuntimeError(f"nodes did not come up: {cell.alive()} (see --log-dir)")
            listener.client.spin(0.2)
        total_s = warmup_s + duration_s
        cell.start(
            "cell_simulator",
            [
                f"wrench_hz:={WRENCH_HZ}",
                f"marker_hz:={MARKER_HZ}",
                f"speed:={SPEED}",
                f"duration_s:={total_s}",
                f"tick_s:={TICK_MS / 1e3}",
                "wait_for_subscribers:=2",  # the identifier (or relay) and the listener: the session starts whole
            ],
        )
        deadline = time.time_ns() + int(30e9)
        while listener.start_ns is None:
            if time.time_ns() > deadline:
                raise RuntimeError("no sim/truth from the simulator")
            listener.client.spin(0.1)
        start = listener.start_ns
        t0, t1 = start + int(warmup_s * 1e9), start + int(total_s * 1e9)
        listener.spin_until(t0)
        first = snapshot(cell)
        rss_series = [first]
        while time.time_ns() < t1:
            listener.spin_until(min(t1, time.time_ns() + int(5e9)))
            rss_series.append(snapshot(cell))
        last = rss_series[-1]
        listener.spin_until(t1 + int(2.5e9))  # the stream has ended: let the identifier report its final counters
        result.update(alive=cell.alive())
    finally:
        cell.close()
        listener.raw.stop.set()
        listener.raw.join(2.0)
        listener.client.close()
    result.update(
        listener=listener, start=start, t0=t0, t1=t1, first=first, last=last, rss_series=rss_series, total_s=total_s
    )
    return result


def report(r: dict[str, Any], duration_s: float) -> list[tuple[str, bool, str]]:
    """Print one mode's figures; return (target, passed, figure) rows."""
    listener: Listener = r["listener"]
    mode, t0, t1, start = r["mode"], r["t0"], r["t1"], r["start"]
    targets: list[tuple[str, bool, str]] = []
    print(
        f"\n=== mode:={mode}, nodes on the {r['executor']} executor  (domain {r['domain']},"
        f" measured {duration_s:.0f} s after the warm-up)"
    )
    if not all(r["alive"].values()):
        print(f"  WARNING: a node exited during the run: {r['alive']}")

    # -- wrench publication and transport ------------------------------------------------------------
    w_stamp, w_pub, w_recv = listener.wrench.arrays(t0, t1, by="stamp")
    seq = (w_stamp - start) // PERIOD_NS
    expected_in_window = int((t1 - t0) // PERIOD_NS)
    print("  wrench /ft_sensor/wrench at the listener")
    print(f"    publication - stamp ({TICK_MS:g} ms ticks)   {stats_ms(w_pub - w_stamp)}")
    print(f"    receive - publication (transport)  {stats_ms(w_recv - w_pub)}")
    print(f"    receive - stamp                    {stats_ms(w_recv - w_stamp)}")
    uniq = np.unique(seq)
    gaps = int(uniq[-1] - uniq[0] + 1 - uniq.size) if uniq.size else 0
    print(f"    received {w_stamp.size} stamped in the measured run (grid: {expected_in_window}), gaps: {gaps}")

    # -- end-to-end latency ----------------------------------------------------------------------------
    relayed = mode in ("recursive", "relay")  # a JointState on bsp/passive_moments per wrench
    stream = listener.passive if relayed else listener.estimate
    topic = "bsp/passive_moments" if relayed else "bsp/estimate"
    e_stamp, e_pub, e_recv = stream.arrays(t0, t1, by="stamp")
    all_stamp, all_pub, all_recv = listener.wrench.arrays(0, 2**62)
    order = np.argsort(all_stamp, kind="stable")
    ws, wp, wr = all_stamp[order], all_pub[order], all_recv[order]
    idx = np.clip(np.searchsorted(ws, e_stamp), 0, max(ws.size - 1, 0))
    matched = (ws[idx] == e_stamp) if ws.size else np.zeros(e_stamp.size, dtype=bool)
    lat_recv = e_recv[matched] - wr[idx[matched]]
    lat_stamp = e_recv[matched] - e_stamp[matched]
    lat_pub = e_pub[matched] - wp[idx[matched]]
    if r.get("dump"):
        np.savez(
            f"{r['dump']}_{mode}_{r['executor']}.npz",
            stamp=e_stamp[matched],
            lat_recv=lat_recv,
            lat_pub=lat_pub,
            start=start,
        )
    print(
        f"  end-to-end latency: wrench -> {topic} stamped with it ({int(matched.sum())} of {e_stamp.size} matched;"
        " invalid estimates carry the wall clock)"
    )
    print(f"    estimate receive - wrench receive  {stats_ms(lat_recv)}   <- primary")
    print(f"    estimate receive - wrench stamp    {stats_ms(lat_stamp)}")
    print(f"    estimate pub - wrench pub (nodes)  {stats_ms(lat_pub)}")
    if mode == "relay":
        print(f"    (the floor: nothing computed) p99 {pct(lat_recv / 1e6, 99):.2f} ms")
    if mode == "recursive":
        p99 = pct(lat_recv / 1e6, 99)
        per_wrench = e_stamp.size / max(expected_in_window, 1)
        print(f"    updates per published wrench: {per_wrench:.3f} (the filter freezes while the arm is still)")
        targets.append(("recursive p99 < 5 ms", bool(lat_recv.size) and p99 < RECURSIVE_P99_MS, f"p99 {p99:.2f} ms"))

    # -- update rate -------------------------------------------------------------------------------------
    _, ea_pub, ea_recv = listener.estimate.arrays(t0, t1)
    valid = np.frombuffer(listener.estimate_valid, dtype=np.int8)
    all_recv_est = np.frombuffer(listener.estimate.recv, dtype=np.int64)
    valid = valid[(all_recv_est >= t0) & (all_recv_est < t1)]
    period_s = 1.0 / UPDATE_HZ
    intervals = np.diff(ea_recv) / 1e9
    pub_intervals = np.diff(ea_pub) / 1e9
    rate = (ea_recv.size - 1) / ((ea_recv[-1] - ea_recv[0]) / 1e9) if ea_recv.size > 1 else 0.0
    late = float((intervals > 1.5 * period_s).mean()) if intervals.size else 1.0
    print(f"  bsp/estimate updates (target {UPDATE_HZ:.0f} Hz), {ea_recv.size} received, {int(valid.sum())} valid")
    if intervals.size:
        print(
            f"    rate {rate:.3f} Hz; interval mean {intervals.mean() * 1e3:.1f} ms, p99 {pct(intervals, 99) * 1e3:.1f}"
            f" ms, max {intervals.max() * 1e3:.1f} ms; later than 1.5 periods: {late:.2%}"
            f" (publisher side p99 {pct(pub_intervals, 99) * 1e3:.1f} ms)"
        )
    timing = [
        r[2] for r in listener.diagnostics.get("bsp_identifier", []) if t0 <= r[1] < t1 and "update_ms_max" in r[2]
    ]
    if timing:
        means = [float(v["update_ms_mean"]) for v in timing]
        print(
            f"    identifier update compute time (its /diagnostics, 10 s windows): mean {np.mean(means):.1f} ms,"
            f" worst window mean {max(means):.1f} ms, max {max(float(v['update_ms_max']) for v in timing):.1f} ms"
        )
        if all("update_cpu_ms_mean" in v for v in timing):
            print(
                "    of which the thread's own CPU time: mean"
                f" {np.mean([float(v['update_cpu_ms_mean']) for v in timing]):.1f} ms,"
                f" max {max(float(v['update_cpu_ms_max']) for v in timing):.1f} ms (the rest: waiting for a core or"
                " for the interpreter)"
            )
    if listener.invalid_reasons:
        top = sorted(listener.invalid_reasons.items(), key=lambda kv: -kv[1])[:3]
        print("    invalid (whole run, after the simulator started): " + "; ".join(f"{n}x {m!r}" for m, n in top))
    if mode == "windowed":
        # Validity is the data's verdict (a window where a joint moved one way only is rightly invalid), so it
        # is reported above but is not part of "on time".
        ok = rate >= 0.99 * UPDATE_HZ and late <= 0.01
        targets.append(("windowed >= 5 Hz on time (rate >= 4.95 Hz, <= 1% late)", ok, f"{rate:.2f} Hz, {late:.1%}"))

    # -- CPU and memory ------------------------------------------------------------------------------------
    first, last = r["first"], r["last"]
    wall = (last.wall_ns - first.wall_ns) / 1e9
    # Shares of the ticks /proc/stat counted, times the cores: on this VM it counts ~15% fewer ticks than
    # cores x wall time, so dividing by the wall time would understate the load.
    ticks = max(last.machine[1] - first.machine[1], 1e-9)
    cores = os.cpu_count() or 1
    busy = (last.machine[0] - first.machine[0]) / ticks * cores
    stolen = (last.machine[2] - first.machine[2]) / ticks * cores
    ours = 0.0
    print(f"  CPU (share of one core over {wall:.0f} s; other threads = Fast DDS's) and RSS")
    flat = True
    growth_text = []
    for name in [*NODES, "listener"]:
        user, system, main_thread = ((b - a) / wall for a, b in zip(first.cpu_s[name], last.cpu_s[name], strict=True))
        cpu = user + system
        ours += cpu
        series = np.array([s.rss_mb[name] for s in r["rss_series"]])
        growth = last.rss_mb[name] - first.rss_mb[name]
        half = series[len(series) // 2 :]
        half_growth = float(half[-1] - half[0])
        trend = half_trend_mb(half)
        print(
            f"    {name:22s} CPU {cpu:6.1%} (sys {system:5.1%}, other threads {cpu - main_thread:5.1%})"
            f"  RSS {first.rss_mb[name]:7.1f} -> {last.rss_mb[name]:7.1f} MB"
            f" (growth {growth:+6.2f} MB; 2nd half {half_growth:+6.2f} MB end to end, trend {trend:+6.2f} MB)"
        )
        if name == "bsp_identifier" and len(series) > 12:
            # The shape of the growth: a few steps that stop (a pool sized to the largest message) or a creep.
            per_minute = " ".join(f"{v:.1f}" for v in series[::12])
            print(f"      {name} RSS every minute of the measured run, MB: {per_minute}")
        if name != "listener":
            flat &= trend < FLAT_MB  # growth: a shrinking RSS is no leak
            growth_text.append(f"{trend:+.2f}")
    # This VM's /proc/stat sometimes counts less busy time than the processes' own counters add up to: then the
    # other processes' share is unknown, not negative.
    others = (
        f"other processes {busy - ours:.0%}"
        if busy >= ours
        else f"other processes unknown (/proc/stat counted less than our processes' own {ours:.0%})"
    )
    print(
        f"    machine busy {busy:.0%} of one core ({cores} cores = {cores}00%), {others};"
        f" stolen by the hypervisor {stolen:.1%} (time no process of this machine ran)"
    )
    targets.append(
        (f"flat memory (2nd-half RSS trend < {FLAT_MB:g} MB per node)", flat, " / ".join(growth_text) + " MB")
    )

    # -- loss ----------------------------------------------------------------------------------------------
    published = int(r["total_s"] * 1e9) // PERIOD_NS + 1  # duration_s caps the stream: samples 0 .. total/period
    final = identifier_counts(listener)
    at_t0 = identifier_counts(listener, t0)
    if final is None:
        print("  loss: no /diagnostics from bsp_identifier")
        targets.append(("zero loss", False, "no counters"))
        return targets
    counts = final[1]
    got = received(counts)
    all_seq = np.unique((np.frombuffer(listener.wrench.stamp, dtype=np.int64) - start) // PERIOD_NS)
    listener_got, highest = int(all_seq.size), int(all_seq[-1]) + 1 if all_seq.size else 0
    print(
        f"  loss: published {published} (stream capped at {r['total_s']:.0f} s; listener saw {listener_got},"
        f" highest seq {highest})"
    )
    print(
        f"    identifier counters: {', '.join(f'{k} {v}' for k, v in counts.items())}"
        f" -> took {got}, lost {published - got} over the whole run"
    )
    at_t1 = identifier_counts(listener, t1)
    if at_t0 is not None and at_t1 is not None:
        # The simulator publishes on a grid (stamp = start + k * PERIOD_NS), so the number published up to a
        # counter's stamp follows from the stamp; the difference to what the identifier took is its loss
        # plus what is still queued (a few samples at most when it keeps up).
        (stamp0, counts0), (stamp1, counts1) = at_t0, at_t1
        published0 = min(published, max(0, (stamp0 - start) // PERIOD_NS + 1))
        published1 = min(published, max(0, (stamp1 - start) // PERIOD_NS + 1))
        warmup_short = published0 - received(counts0)
        measured_short = (published1 - published0) - (received(counts1) - received(counts0))
        # Negative: samples still queued at the warm-up's end were taken during the measured run.
        measured = (
            f"{measured_short}" if measured_short >= 0 else f"0 (and {-measured_short} queued at the warm-up's end)"
        )
        print(
            f"    not taken by the identifier: {warmup_short} of {published0} by the end of the warm-up (lost or"
            f" queued), {measured} of {published1 - published0} during the measured run"
        )
    targets.append(("zero loss over the whole run", published == got, f"{published - got} lost"))
    return targets


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--duration", type=float, default=600.0, help="measured seconds per mode (after warm-up)")
    parser.add_argument("--warmup", type=float, default=20.0, help="seconds before measuring")
    parser.add_argument(
        "--modes",
        default="windowed,recursive",
        help="comma-separated identifier modes; relay: the latency floor (bench/relay_node.py, nothing computed)",
    )
    parser.add_argument(
        "--executors", default="events,single", help="comma-separated node executors (BSP_EXECUTOR), side by side"
    )
    parser.add_argument("--domain", type=int, default=60 + (os.getpid() % 20) * 2, help="first private domain id")
    parser.add_argument("--log-dir", default=None, help="keep the nodes' output here")
    parser.add_argument("--dump", default=None, help="save per-wrench latencies to <DUMP>_<mode>_<executor>.npz")
    args = parser.parse_args()
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # unwind, so that the nodes are stopped too
    signal.signal(signal.SIGINT, signal.default_int_handler)  # also when started in the background
    modes = [m.strip() for m in args.modes.split(",") if m.strip()]
    if args.log_dir:
        os.makedirs(args.log_dir, exist_ok=True)
    with open("/proc/loadavg") as f:
        load = f.read().split()[:3]
    print(
        f"live cell: wrench {WRENCH_HZ:.0f} Hz, markers {MARKER_HZ:.0f} Hz, speed {SPEED}, {args.duration:.0f} s"
        f" per mode after {args.warmup:.0f} s warm-up; {os.cpu_count()} cores, load average {' '.join(load)}"
    )
    executors = [e.strip() for e in args.executors.split(",") if e.strip()]
    rows: list[tuple[str, str, bool, str]] = []
    runs = [(mode, executor) for mode in modes for executor in executors]
    for k, (mode, executor) in enumerate(runs):
        label = f"{mode}/{executor}"
        log_dir = os.path.join(args.log_dir, mode, executor) if args.log_dir else None
        if log_dir:
            os.makedirs(log_dir, exist_ok=True)
        result = run_mode(mode, executor, args.domain + k, args.duration, args.warmup, log_dir)
        result["dump"] = args.dump
        rows += [(label, *t) for t in report(result, args.duration)]
    print("\ntargets")
    for label, name, ok, figure in rows:
        print(f"  {'PASS' if ok else 'FAIL'}  {label:16s} {name:62s} {figure}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
