"""Pseudonymous subject ids: short opaque tokens, never names."""

from __future__ import annotations

import re

from bsp_ros.errors import InputError

SUBJECT_PATTERN = re.compile(r"[A-Za-z0-9_-]{1,64}")


def check_subject_id(subject: object) -> str:
    """Return ``subject`` if it is a pseudonymous id: 1-64 characters from ``A-Z a-z 0-9 _ -``.

    Parameters
    ----------
    subject : object
        The id to check.

    Returns
    -------
    str
        The id, unchanged.

    Raises
    ------
    InputError
        If it is not a string, is empty or over-long, or holds spaces, dots, ``@`` or other characters
        that names, e-mail addresses or paths need (the mapping to a person lives elsewhere).
    """
    if not isinstance(subject, str):
        raise InputError(f"subject id must be a string, got {type(subject).__name__}")
    if not subject.strip():
        raise InputError("subject id must not be empty")
    if len(subject) > 64:
        raise InputError(f"subject id must be at most 64 characters, got {len(subject)}")
    if SUBJECT_PATTERN.fullmatch(subject) is None:
        raise InputError(
            f"subject id {subject!r} is not a pseudonym: use 1-64 characters from A-Z a-z 0-9 _ - "
            "(no spaces, names or e-mail addresses)"
        )
    return subject
