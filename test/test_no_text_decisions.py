"""Nobody decides on a finding's rendered text: the patterns that once matched text to decide come back nowhere.

Every decision switches on a finding's code and values (``bsp_ros.core.findings``), never on the text rendered from
them (docs/contract.md: "decide on ``code``, never on the text"). This greps the product, the benches, the scripts
and the tests for the shapes such a decision took, and fails where one comes back.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCANNED = ("bsp_ros", "bench", "scripts", "test")

# An estimate's warnings: in its JSON, its typed quality or an identification result.
_WARNINGS = r"""([\w.]*\[["']quality["']\]\[["']warnings["']\]|quality\[["']warnings["']\]|result\.warnings)"""
# A message: an attribute, a key or a key read with a default (an estimate's, a run's row, a diagnostic status').
_MESSAGE = r"""(\.message\b|\[["']message["']\]|\.get\(["']message["'])"""

# Each pattern and what it catches. The estimate's ``message`` joins the invalid findings' texts and ``warnings``
# holds the others': a substring, split or prefix of either decides on text.
PATTERNS = {
    "a message split into clauses": re.compile(r"""(\bmessage|\[["']message["']\])\.split\("""),
    "a message's or warning's prefix": re.compile(
        r"""(\.message|\[["']message["']\]|\[["']warnings["']\]\[\d+\])\.startswith\("""
    ),
    "a warning's prefix": re.compile(r"""\.startswith\(\(?["'](confounded|uncertain)"""),
    "a substring of an estimate's message": re.compile(
        r"""["'] in (result\.message|[\w.]*\[["']quality["']\]\[["']message["']\]|quality\[["']message["']\])"""
    ),
    # A string literal tested with ``in``, or a prefix, on a line that iterates an estimate's warnings.
    "a substring of an estimate's warnings": re.compile(
        rf"""((["'] in \w+\b|\.startswith\().*\bfor \w+ in {_WARNINGS}|\bfor \w+ in {_WARNINGS}.*["'] in \w+\b)"""
    ),
    "a stale input told by its text": re.compile(r"""["']stale["'] in """),
    "a --passive model parsed out of a text": re.compile(r"""re\.compile\(r?["']--passive"""),
    # Counting alike messages or warnings together: their numbers blanked, or each one mapped to a "kind".
    "a message's numbers blanked to group it": re.compile(rf"""\.sub\(.*{_MESSAGE}"""),
    "a count keyed by a message": re.compile(rf"""\w\[\w+\((str\()?[\w.]*(\[["']\w+["']\])*{_MESSAGE}"""),
    # A function of each warning (``str`` only converts it) in a comprehension over an estimate's warnings.
    "a kind made of each warning's text": re.compile(
        rf"""\b(?!str\b)\w+\((\w+|str\(\w+\))\) for \w+ in ({_WARNINGS}|.*\.get\(["']warnings["'])"""
    ),
}

# Tests of the rendering itself: they check that a text reads right, having decided on codes what happened.
RENDERING_TESTS = {
    "test/bsp_ros/core/test_findings.py": "how findings join into an estimate's message and warnings",
}


def _sources() -> list[Path]:
    return sorted(p for top in SCANNED for p in (ROOT / top).rglob("*.py") if p != Path(__file__).resolve())


def _hits(text: str) -> list[tuple[int, str]]:
    return [
        (number, what)
        for number, line in enumerate(text.splitlines(), start=1)
        for what, pattern in PATTERNS.items()
        if pattern.search(line)
    ]


def test_no_source_decides_on_a_finding_s_text() -> None:
    found = []
    for path in _sources():
        relative = path.relative_to(ROOT).as_posix()
        if relative in RENDERING_TESTS:
            continue
        found += [f"{relative}:{number}: {what}" for number, what in _hits(path.read_text("utf-8"))]
    assert not found, "\n".join(found)


@pytest.mark.parametrize(
    "line",
    [
        'first = message.split(";")[0]; quality.message.split(";")',
        'quality["message"].startswith("missing transform")',
        'head = warning if not warning.startswith(("confounded", "uncertain")) else ""',
        'assert "does not fit" in quality["message"]',
        'assert "bound 0" in document["quality"]["message"]',
        'assert "lacks" in result.message',
        'assert any("drifts" in w for w in result.warnings)',
        'assert any("elastic" in w for w in document["quality"]["warnings"])',
        'held = [w for w in result.warnings if "Stribeck" in w]',
        'assert not any(w.startswith("the markers sit further off") for w in quality["warnings"])',
        'first = message.split(";")[0].split(":")[0]',
        'lambda: "stale" in _latest(c)["quality"]["message"]',
        '_SUGGESTION = re.compile(r"--passive ([a-z]+)")',
        'estimate["quality"]["warnings"][0].startswith("bag damaged")',
        'for kind in dict.fromkeys(_kind(w) for w in document["quality"]["warnings"]):',
        'messages[_kind(document["quality"]["message"])] += 1',
        'messages = collections.Counter(re.sub(r"[-+]?\\d[\\d.e+-]*", "#", r["message"])[:80] for r in runs)',
        'messages.append(_NUMBER.sub("#", str(estimate.document["quality"].get("message", "")))[:70])',
        'messages = [_NUMBER.sub("#", str(d["quality"]["message"]))[:70] for d in documents]',
        'reason = re.sub(r"[0-9.]+", "#", quality[0].message if quality else "no quality status")',
        '"warnings": [_kind(w) for w in document["quality"]["warnings"]],',
        "held = {_kind(str(w)) for w in result.warnings}",
        'kinds = collections.Counter(_kind(w) for w in estimate.get("quality", {}).get("warnings", []))',
    ],
)
def test_each_pattern_catches_the_shape_it_names(line: str) -> None:
    assert _hits(line), line


@pytest.mark.parametrize(
    "line",
    [
        "assert FindingCode.INPUT_STALE in [f.code for f in findings_of(quality)]",
        "assert result.valid, result.message  # the text only explains a failure",
        'assert any("no CRC" in w for w in report.warnings)  # a bag reader\'s own notes have no code',
        'assert "ros2 param set /session_recorder subject" in reply.message  # a service reply',
        'causes[cause_of(document["quality"])] += 1',
        "for kind in dict.fromkeys(warning_kinds(document['quality'])):",
        'return _NUMBER.sub("#", str(document["error"]))[:70]  # a run that wrote no estimate: the CLI\'s error line',
        'print(f"{n}x {m!r}" for m, n in top)',
        'warnings=tuple(str(w) for w in block.get("warnings") or ()),  # a conversion',
        'messages = collections.Counter(r["message"] for r in runs if not r["valid"])  # a row\'s cause, not a text',
    ],
)
def test_deciding_on_codes_and_other_layers_texts_pass(line: str) -> None:
    assert not _hits(line), line
