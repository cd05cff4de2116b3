"""A topic whose publisher's type is not installed here is refused by type, and a recording of nothing names it."""

from __future__ import annotations

import threading
from collections.abc import Sequence
from pathlib import Path

import pytest
from ros_domains import next_domain_id

from bsp_ros.errors import DataError
from bsp_ros.live import recorder
from bsp_ros.live.runtime.ros import has_message

MISSING_TYPE = "bsp_absent_msgs/msg/Nothing"


def test_a_topic_whose_type_is_not_installed_is_named_in_the_error_of_an_empty_recording(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert not has_message(MISSING_TYPE)

    stop = threading.Event()

    # The graph as rclpy would list it: a publisher of /arm/thing whose message package this machine lacks (the
    # recorder's real subscribe then fails to load the type). The DDS graph cannot hold such a publisher here:
    # a peer could only publish a type installed in this venv. The recording stops once it was looked up.
    def discovered(self: recorder._Recorder, topics: Sequence[str]) -> dict[str, dict[bytes, recorder._Publisher]]:
        stop.set()
        publisher = recorder._Publisher(msgtype=MISSING_TYPE, profile={}, reliable=True, transient_local=False)
        return {"/arm/thing": {b"gid": publisher}} if "/arm/thing" in topics else {}

    monkeypatch.setattr(recorder._Recorder, "discovered", discovered)
    out = tmp_path / "bag"
    with pytest.raises(DataError) as raised:
        recorder.record(["/arm/thing"], out, domain_id=next_domain_id(), stop=stop)
    message = str(raised.value)
    # One line naming the topic and why; no empty bag left behind.
    assert "\n" not in message and "; /arm/thing: cannot subscribe (" in message and "bsp_absent_msgs" in message
    assert not out.exists()
