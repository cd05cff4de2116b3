"""A topic named for two roles: the wrench role's type is required, so poses are never decoded as wrenches."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest

from bsp_ros.bag import POSE_TYPE, WRENCH_TYPE, MessageTypeError, TopicMap, read_session
from bsp_ros.core.simulation import SimulatedSession


def test_a_marker_topic_given_as_the_wrench_topic_fails_the_type_check(
    human_session: SimulatedSession, write_bag: Callable[..., Path]
) -> None:
    bag = write_bag(human_session)
    with pytest.raises(MessageTypeError) as raised:
        read_session(bag, topics=TopicMap(wrench="/mocap/hand"))
    assert raised.value.topic == "/mocap/hand"
    assert raised.value.expected == WRENCH_TYPE
    assert raised.value.found == [POSE_TYPE]
