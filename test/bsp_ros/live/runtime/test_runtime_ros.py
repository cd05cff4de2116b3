"""Message classes by type name, the install hint, and the parameter table."""

from __future__ import annotations

import importlib.util

import pytest

from bsp_ros.errors import RuntimeBackendError
from bsp_ros.live.runtime.parameters import Param, help_text, wants_help
from bsp_ros.live.runtime.ros import has_message, message_class


def test_message_classes_come_from_the_installed_packages() -> None:
    from geometry_msgs.msg import WrenchStamped

    assert message_class("geometry_msgs/msg/WrenchStamped") is WrenchStamped
    assert message_class("geometry_msgs/WrenchStamped") is WrenchStamped


def test_a_missing_package_is_named_with_how_to_install_it() -> None:
    with pytest.raises(RuntimeBackendError, match=r"no_such_msgs/msg/Thing.*'no_such_msgs'.*ros-jazzy-no-such-msgs"):
        message_class("no_such_msgs/msg/Thing")


def test_a_missing_message_and_a_malformed_name_are_named() -> None:
    with pytest.raises(RuntimeBackendError, match=r"geometry_msgs/msg/NoSuch.*'NoSuch'"):
        message_class("geometry_msgs/msg/NoSuch")
    with pytest.raises(RuntimeBackendError, match="pkg/msg/Type"):
        message_class("geometry_msgs/srv/Wrench")


def test_tf2_msgs_is_found_exactly_when_importable() -> None:
    assert has_message("tf2_msgs/msg/TFMessage") == (importlib.util.find_spec("tf2_msgs") is not None)


def test_help_is_asked_before_the_ros_arguments_only() -> None:
    assert wants_help(["node", "--help"]) and wants_help(["node", "-h", "--ros-args", "-p", "a:=1"])
    assert not wants_help(["node", "--ros-args", "-p", "a:=1"])
    assert not wants_help(["node", "--ros-args", "-r", "__node:=-h"])


def test_help_text_shows_type_default_unit_and_range() -> None:
    params = (
        Param(name="rate_hz", default=5.0, description="estimate rate", unit="Hz", lo=0.1, hi=100.0),
        Param(name="mode", default="a", description="mode", choices=("a", "b")),
    )
    text = help_text("demo_node", "Does things.", params)
    assert "rate_hz  float default 5.0" in text and "[Hz] (range 0.1 .. 100)" in text
    assert "(one of a, b)" in text
