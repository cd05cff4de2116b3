"""The documents a user is pointed to exist in a clone, and the README's commands table lists every option."""

from __future__ import annotations

import ast
import importlib.util
import re
import subprocess
from pathlib import Path

import pytest

from bsp_ros.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
# Markdown read by users: the README, the benchmarks, the sample bags' notes and everything under docs/.
DOCUMENTS = ["README.md", "bench/README.md", "bags/README.md", *sorted(p.name for p in (ROOT / "docs").glob("*.md"))]
# A repository path as the documents and messages write it: docs/x.md, bench/x.py, scripts/x.py, bags/...
PATH_PATTERN = re.compile(r"(?<![\w/.])((?:docs|bench|scripts|bags)/[\w./-]*[\w])")
LINK_PATTERN = re.compile(r"\]\(([^)#\s]+)")
FOREIGN = ("CONTRACT.md", "../shared", "shared/reference")


def _document_path(name: str) -> Path:
    return ROOT / name if "/" in name or name == "README.md" else ROOT / "docs" / name


def _tracked() -> set[str]:
    """Files a fresh clone has: git's index (the working tree's files where git is not available)."""
    try:
        done = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        return {str(p.relative_to(ROOT)) for p in ROOT.rglob("*") if p.is_file()}
    files = set(done.stdout.split())
    return files | {str(Path(f).parent) for f in files} | {str(p) for f in files for p in Path(f).parents}


def _named_paths(text: str, base: Path) -> set[str]:
    """Repository paths a text names: its relative markdown links (resolved from ``base``) and written paths."""
    names = {m for m in PATH_PATTERN.findall(text)}
    for link in LINK_PATTERN.findall(text):
        if "://" in link or link.startswith("mailto:"):
            continue
        names.add(str((base / link).resolve().relative_to(ROOT)))
    return {name.rstrip(".") for name in names}


def _message_strings() -> dict[str, str]:
    """Every string literal of bsp_ros that is not a docstring (messages, reports, help texts), by module."""
    out = {}
    for path in sorted((ROOT / "bsp_ros").rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        docstrings = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef) and node.body:
                first = node.body[0]
                if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                    docstrings.add(id(first.value))
        texts = [
            node.value
            for node in ast.walk(tree)
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings
        ]
        out[str(path.relative_to(ROOT))] = "\n".join(texts)
    return out


@pytest.mark.parametrize("document", DOCUMENTS)
def test_every_path_a_document_names_is_in_a_fresh_clone(document: str) -> None:
    path = _document_path(document)
    assert path.is_file(), document
    text = path.read_text(encoding="utf-8")
    missing = sorted(_named_paths(text, path.parent) - _tracked())
    assert missing == [], f"{document} names files a clone does not have: {missing}"
    assert not [word for word in FOREIGN if word in text], f"{document} points outside the repository"


def test_every_path_a_message_or_the_report_names_is_in_a_fresh_clone() -> None:
    tracked = _tracked()
    for module, text in _message_strings().items():
        missing = sorted(_named_paths(text, ROOT) - tracked)
        assert missing == [], f"{module} names files a clone does not have: {missing}"
        assert not [word for word in FOREIGN if word in text], f"{module} points outside the repository"


def test_the_new_documents_are_named_by_the_readme_and_by_the_demo() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    for name in ("docs/contract.md", "docs/method.md", "docs/cell-guide.md", "docs/clinic.md", "bench/README.md"):
        assert f"]({name})" in readme, name
    assert "docs/cell-guide.md" in _message_strings()["bsp_ros/cli/demo.py"]


def _readme_commands() -> object:
    spec = importlib.util.spec_from_file_location("readme_commands", ROOT / "scripts" / "readme_commands.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_readme_commands_table_lists_every_subcommand_and_option() -> None:
    section = (ROOT / "README.md").read_text(encoding="utf-8").split("\n## Commands\n", 1)[1].split("\n## ", 1)[0]
    table_rows = [line for line in section.splitlines() if line.startswith("| `bsp ")]
    rows = {line.split("`")[1]: line for line in table_rows}
    generated = list(_readme_commands().command_rows(build_parser()))  # type: ignore[attr-defined]
    assert len(generated) >= 9
    for command, options, _ in generated:
        assert command in rows, f"the README's commands table has no row for `{command}`"
        for option in options:
            assert option in rows[command], f"`{command}` lacks {option} in the README's commands table"
    assert len(rows) == len(generated), "the README lists a command the parser does not have"
