"""Frozen dataclasses whose arguments are checked and converted before they are stored, never after."""

from __future__ import annotations

import dataclasses
import functools
import inspect
from types import SimpleNamespace
from typing import Any, Protocol, TypeVar


class Normalising(Protocol):
    """A class that checks and converts its arguments before they are stored."""

    @staticmethod
    def normalise(given: Any) -> dict[str, Any]:
        """The arguments (the attributes of ``given``, one per field) checked; the converted ones by name."""
        ...


T = TypeVar("T", bound=Normalising)


def normalising(cls: type[T]) -> type[T]:
    """``cls``, a frozen dataclass with a static method ``normalise(given) -> dict``, built from its arguments
    checked and converted.

    ``cls(...)`` binds its arguments as the dataclass's ``__init__`` would (defaults and default factories
    filled in) and hands them to ``cls.normalise`` as the attributes of ``given``; that raises on a bad value
    and returns the converted ones by field name (a tuple of floats for a list or an array, a float for an
    int, a default expanded). The dataclass's own ``__init__`` then stores every field once, converted where
    ``normalise`` said so. Nothing writes to the instance afterwards: it is frozen from the start.
    """
    store = cls.__init__
    signature = inspect.signature(store)
    fields = [f for f in dataclasses.fields(cls) if f.init]  # type: ignore[arg-type]

    @functools.wraps(store)
    def init(self: T, *args: Any, **kwargs: Any) -> None:
        given = signature.bind(self, *args, **kwargs).arguments
        del given["self"]
        for f in fields:
            if f.name not in given:
                given[f.name] = f.default if f.default_factory is dataclasses.MISSING else f.default_factory()
        store(self, **(given | cls.normalise(SimpleNamespace(**given))))

    setattr(cls, "__init__", init)  # noqa: B010 (the dataclass's own __init__, wrapped)
    return cls
