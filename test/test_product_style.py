"""The product's standing rules that a reviewer would otherwise check by hand.

Short functions in the core; a README that stays an entry point; product text that says why, never when or in
which round of work; the documents the README promises; the core's import direction (static, every import
statement, including those inside functions; test/bsp_ros/core/test_core_purity.py checks what importing loads).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "bsp_ros" / "core"
MAX_FUNCTION_LINES = 80
MAX_README_LINES = 200
# Development history in product text: "the 3rd session", "issue 12", "this round", "mended on".
HISTORY = re.compile(r"[0-9]+(st|nd|rd|th) session|issue [0-9]+|this round|mended on", re.IGNORECASE)
PRODUCT_TEXT = ("README.md", "docs", "bsp_ros", "msg_adapters", "bench/README.md")
TEXT_SUFFIXES = {".py", ".md", ".yaml", ".yml", ".txt", ".html", ".css", ".js", ".xml", ".cfg", ".toml"}
# The core depends on nothing of the package's outer layers and on no middleware or message package.
OUTER_LAYERS = ("bsp_ros.bag", "bsp_ros.live", "bsp_ros.clinic", "bsp_ros.cli")
MIDDLEWARE = ("rclpy", "rosbags", "mcap", "cyclonedds", "std_srvs", "msg_adapters")


def _core_modules() -> list[Path]:
    return sorted(CORE.rglob("*.py"))


def _function_lengths(source: str, label: str) -> list[tuple[str, int]]:
    """(``label:line name``, lines from ``def`` to the body's last line) of every function, nested ones too."""
    return [
        (f"{label}:{node.lineno} {node.name}", (node.end_lineno or node.lineno) - node.lineno + 1)
        for node in ast.walk(ast.parse(source, filename=label))
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
    ]


def _imported_modules(source: str, package: str) -> list[str]:
    """Every module an import statement names, relative imports resolved against ``package`` (the module's)."""
    names: list[str] = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package.rsplit(".", node.level - 1)[0] if node.level else ""
            module = ".".join(filter(None, [base, node.module or ""]))
            names += [module] + [f"{module}.{alias.name}" for alias in node.names]
    return names


def _package_of(path: Path) -> str:
    return ".".join(path.relative_to(ROOT).with_suffix("").parts[:-1])


def _product_text_files() -> list[Path]:
    files: list[Path] = []
    for name in PRODUCT_TEXT:
        path = ROOT / name
        candidates = [path] if path.is_file() else sorted(path.rglob("*"))
        files += [p for p in candidates if p.is_file() and p.suffix in TEXT_SUFFIXES and "__pycache__" not in p.parts]
    return files


def test_no_core_function_is_longer_than_80_lines() -> None:
    lengths = [
        item
        for path in _core_modules()
        for item in _function_lengths(path.read_text(encoding="utf-8"), str(path.relative_to(ROOT)))
    ]
    assert len(lengths) > 500  # the walk sees the core's functions, nested ones included
    too_long = [f"{name} ({n} lines)" for name, n in lengths if n > MAX_FUNCTION_LINES]
    assert not too_long, "split these functions: " + "; ".join(too_long)


def test_the_length_check_counts_a_function_from_def_to_its_last_line() -> None:
    body = "\n".join(f"        x{k} = {k}" for k in range(MAX_FUNCTION_LINES))
    source = f"class A:\n    def long(self):\n{body}\n\n\ndef short():\n    return 1\n"
    lengths = {name.split(" ")[-1]: n for name, n in _function_lengths(source, "example.py")}
    assert lengths == {"long": MAX_FUNCTION_LINES + 1, "short": 2}


def test_the_readme_stays_an_entry_point_under_200_lines() -> None:
    lines = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    assert len(lines) < MAX_README_LINES, f"README.md has {len(lines)} lines: move detail into docs/"


def test_product_text_carries_no_development_history() -> None:
    files = _product_text_files()
    assert any(p.name == "architecture.md" for p in files) and any(p.suffix == ".py" for p in files)
    hits = [
        f"{path.relative_to(ROOT)}:{number}: {line.strip()[:100]}"
        for path in files
        for number, line in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1)
        if HISTORY.search(line)
    ]
    assert not hits, "say why, not when (the history belongs in CHANGES.md and commits):\n" + "\n".join(hits)


def test_the_history_pattern_finds_what_it_is_meant_to() -> None:
    for text in ("as in the 3rd session", "see Issue 12", "changed this round", "Mended on Tuesday"):
        assert HISTORY.search(text), text
    for text in ("a session of 40 s", "the 2nd joint", "an issue with the sensor"):
        assert not HISTORY.search(text), text


def test_the_readme_links_the_architecture_and_the_changes() -> None:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    for name in ("docs/architecture.md", "CHANGES.md"):
        assert (ROOT / name).is_file(), name
        assert f"]({name})" in readme, f"README.md does not link {name}"


def test_the_core_imports_nothing_of_the_outer_layers_or_the_middleware() -> None:
    offending = []
    for path in _core_modules():
        for module in _imported_modules(path.read_text(encoding="utf-8"), _package_of(path)):
            top = module.split(".")[0]
            if module.startswith(OUTER_LAYERS) or top in MIDDLEWARE or top.endswith("_msgs"):
                offending.append(f"{path.relative_to(ROOT)}: {module}")
    assert not offending, "the core imports outward:\n" + "\n".join(offending)


def test_the_import_check_sees_imports_inside_functions_and_relative_ones() -> None:
    source = "import numpy\n\ndef f():\n    from ...cli import main\n    from . import model\n    import rclpy.node\n"
    names = _imported_modules(source, "bsp_ros.core.identification")
    assert names == [
        "numpy",
        "bsp_ros.cli",
        "bsp_ros.cli.main",
        "bsp_ros.core.identification",
        "bsp_ros.core.identification.model",
        "rclpy.node",
    ]
