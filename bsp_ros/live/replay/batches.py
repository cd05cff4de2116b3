"""A bag's raw messages as log-time ordered batches, scanned (CRC-checked) in a thread ahead of the playback."""

from __future__ import annotations

import queue
import threading
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from bsp_ros.bag.mcap_scan import ChannelInfo, ScanResult, scan_mcap

Batch = list[tuple[int, str, bytes]]  # (log_ns, topic, raw CDR), in log-time order


class _BatchSink:
    """Turns the scanner's per-channel feeds into log-time ordered batches of raw messages."""

    def __init__(self, wanted: Callable[[ChannelInfo], bool], out: Callable[[Batch], None]) -> None:
        self._wanted = wanted
        self._out = out
        self._buf: np.ndarray | None = None
        self._parts: list[tuple[np.ndarray, np.ndarray, list[str], list[bytes]]] = []

    def wants(self, channel: ChannelInfo) -> bool:
        return self._wanted(channel)

    def feed(
        self, channel: ChannelInfo, buf: np.ndarray, offsets: np.ndarray, lengths: np.ndarray, log_ns: np.ndarray
    ) -> None:
        if self._buf is not None and buf is not self._buf:
            self.flush()
        self._buf = buf
        data = [buf[o : o + n].tobytes() for o, n in zip(offsets.tolist(), lengths.tolist(), strict=True)]
        self._parts.append((log_ns, offsets, [channel.topic] * len(data), data))

    def flush(self) -> None:
        """Emit what was fed since the last flush, sorted by log time (ties: file order)."""
        if not self._parts:
            return
        log = np.concatenate([p[0] for p in self._parts])
        where = np.concatenate([p[1] for p in self._parts])
        topics = [t for p in self._parts for t in p[2]]
        data = [d for p in self._parts for d in p[3]]
        self._parts.clear()
        self._buf = None
        order = np.lexsort((where, log))
        self._out([(int(log[i]), topics[i], data[i]) for i in order.tolist()])


def scan_thread(
    files: Sequence[Path],
    wanted: Callable[[ChannelInfo], bool],
    batches: queue.Queue[Batch | ScanResult | BaseException | None],
    stop: threading.Event,
) -> threading.Thread:
    """Start a thread that scans ``files`` and puts batches, then each file's ScanResult, then None."""

    def put(item: Batch | ScanResult | BaseException | None) -> None:
        while not stop.is_set():
            try:
                batches.put(item, timeout=0.1)
                return
            except queue.Full:
                continue
        raise _StoppedError

    def work() -> None:
        try:
            for file in files:
                sink = _BatchSink(wanted, put)
                result = scan_mcap(file, sink)
                sink.flush()
                put(result)
            put(None)
        except _StoppedError:
            return
        except BaseException as error:  # handed to the playing thread
            try:
                put(error)
            except _StoppedError:
                return

    thread = threading.Thread(target=work, name="bsp_ros-play-scan", daemon=True)
    thread.start()
    return thread


class _StoppedError(Exception):
    """The playback was stopped while the scanner waited."""
