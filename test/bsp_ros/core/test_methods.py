"""The identification method and the live mode are StrEnums whose words are the ones the JSON, the CLI and the
node's parameters have always carried."""

from __future__ import annotations

import pytest

from bsp_ros.cli.identify_options import METHODS as CLI_METHODS
from bsp_ros.core.methods import OFFLINE_METHODS, LiveMode, Method
from bsp_ros.core.pipeline import METHODS, IdentifyOptions
from bsp_ros.errors import InputError
from bsp_ros.live.online.identifier_settings import MODES, IdentifierSettings


def test_the_words_are_those_of_the_contract() -> None:
    assert [m.value for m in Method] == ["joint", "paper", "recursive"]
    assert [m.value for m in LiveMode] == ["windowed", "recursive"]
    # The parsers' choices stay plain words (their error messages name them): the same as the enums'.
    assert METHODS == CLI_METHODS == ("joint", "paper") == tuple(OFFLINE_METHODS)
    assert MODES == ("windowed", "recursive")


def test_the_settings_and_options_hold_members() -> None:
    settings = IdentifierSettings.from_parameters({"mode": "recursive", "method": "paper"})
    assert settings.mode is LiveMode.RECURSIVE and settings.options.method is Method.PAPER
    assert IdentifierSettings.from_parameters({}).mode is LiveMode.WINDOWED
    assert IdentifyOptions().method is Method.JOINT


def test_an_unknown_method_is_refused_naming_the_choices() -> None:
    with pytest.raises(InputError, match=r"method must be one of \('joint', 'paper'\), got 'stacked'"):
        IdentifyOptions(method="stacked")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="mode"):
        IdentifierSettings.from_parameters({"mode": "batch"})
