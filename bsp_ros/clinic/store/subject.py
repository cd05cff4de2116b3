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


_DATE_PATTERNS = (
    re.compile(r"(?<!\d)(19\d\d|20\d\d)[-_.]?(0[1-9]|1[0-2])[-_.]?(0[1-9]|[12]\d|3[01])(?!\d)"),  # 1984-03-12
    re.compile(r"(?<!\d)(0[1-9]|[12]\d|3[01])[-_.]?(0[1-9]|1[0-2])[-_.]?(19\d\d|20\d\d)(?!\d)"),  # 12-03-1984
)
# A capitalised word of two or more letters: "Maria", "Garcia" (also inside CamelCase "MariaGarcia").
_NAME_WORD = re.compile(r"[A-Z][a-z]+")


def identifying_reason(subject: str) -> str | None:
    """Why ``subject`` looks like it identifies a person (a birth date or a name), or None if it does not.

    A heuristic, not a guarantee: it catches ``Maria_Garcia_1984-03-12``, ``garcia_19840312`` and
    ``MariaGarcia``; it passes ``P007``, ``S01``, ``stroke-03``.
    """
    for pattern in _DATE_PATTERNS:
        found = pattern.search(subject)
        if found:
            return f"it holds {found.group(0)!r}, which reads as a date (a birth date identifies a person)"
    words = [w for w in _NAME_WORD.findall(subject) if len(w) >= 2]
    if len(words) >= 2:
        return f"it holds the capitalised words {', '.join(map(repr, words))}, which read as a person's name"
    return None


def check_pseudonymous_id(subject: object, *, allow_identifying: bool = False) -> str:
    """Return ``subject`` if :func:`check_subject_id` passes and it does not look like a name or birth date.

    Raises
    ------
    InputError
        If the id is malformed, or looks identifying (:func:`identifying_reason`) and ``allow_identifying``
        is False; the message gives the reason and the override (``--allow-identifying-id``).
    """
    subject = check_subject_id(subject)
    reason = None if allow_identifying else identifying_reason(subject)
    if reason is not None:
        raise InputError(
            f"subject id {subject!r} looks like it identifies a person: {reason}. Use a pseudonym such as "
            "P007 (keep the mapping to the person elsewhere), or pass --allow-identifying-id if it is not one"
        )
    return subject
