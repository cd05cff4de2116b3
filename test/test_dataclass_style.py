"""The package's dataclasses keep two house rules that a reviewer would otherwise check by hand.

- A wide dataclass (8 or more fields, its dataclass bases' included) is ``kw_only=True``: it is built by keyword,
  so a field added, removed or moved cannot shift the others' values silently.
- A frozen dataclass is never written after construction: nothing in the package calls ``object.__setattr__``
  (or ``__delattr__``, or ``super()``'s) or writes through an instance's ``__dict__`` or ``vars()``, the ways
  around ``frozen=True``.

Both are read from the source (every module of bsp_ros/ and msg_adapters/, parsed, never imported), so a node
module that needs rclpy is checked like any other. The scanners are tested on small sources first, with and
without each breach, so that a scanner that finds nothing cannot pass for a clean package.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("bsp_ros", "msg_adapters")
WIDE_FIELDS = 8
# Calls that set or delete an attribute past a frozen dataclass's own __setattr__.
BYPASS_ATTRIBUTES = {"__setattr__", "__delattr__"}
# Methods of a dict that change it: called on an instance's __dict__ or vars() they write the instance.
DICT_WRITES = {"__setitem__", "__delitem__", "update", "setdefault", "pop", "popitem", "clear"}


@dataclass(frozen=True, kw_only=True)
class DataclassInfo:
    """One class decorated ``@dataclass`` / ``@dataclasses.dataclass``, as the source declares it."""

    where: str  # "path:line Name"
    module: str  # dotted module name
    name: str
    n_own_fields: int  # annotated class attributes, ClassVar and the KW_ONLY marker left out
    kw_only: bool
    frozen: bool
    bases: tuple[str, ...]  # dotted names of the bases' classes, as far as the module's imports resolve them


def _dataclass_options(node: ast.ClassDef) -> dict[str, bool] | None:
    """The literal boolean options of ``node``'s dataclass decorator, or None if it has none."""
    for decorator in node.decorator_list:
        target = decorator.func if isinstance(decorator, ast.Call) else decorator
        name = target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", None)
        if name != "dataclass":
            continue
        keywords = decorator.keywords if isinstance(decorator, ast.Call) else []
        return {k.arg: k.value.value is True for k in keywords if k.arg and isinstance(k.value, ast.Constant)}
    return None


def _is_field(statement: ast.stmt) -> bool:
    if not (isinstance(statement, ast.AnnAssign) and isinstance(statement.target, ast.Name)):
        return False
    annotation = statement.annotation
    head = annotation.value if isinstance(annotation, ast.Subscript) else annotation
    if isinstance(head, ast.Constant):  # a quoted annotation, "ClassVar[int]"
        return not str(head.value).startswith(("ClassVar", "KW_ONLY"))
    name = head.attr if isinstance(head, ast.Attribute) else getattr(head, "id", None)
    return name not in ("ClassVar", "KW_ONLY")


def _imported_names(tree: ast.Module, module: str) -> dict[str, str]:
    """Local name -> dotted name of every ``from X import Y`` in ``tree`` (relative ones resolved)."""
    package = module.rsplit(".", 1)[0]
    names: dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            base = package.rsplit(".", node.level - 1)[0] if node.level else ""
            source = ".".join(filter(None, [base, node.module or ""]))
            names.update({alias.asname or alias.name: f"{source}.{alias.name}" for alias in node.names})
    return names


def dataclasses_in(source: str, module: str, label: str) -> list[DataclassInfo]:
    """Every dataclass ``source`` (the module ``module``, shown as ``label``) declares, nested ones too."""
    tree = ast.parse(source, filename=label)
    imported = _imported_names(tree, module)
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.ClassDef) or (options := _dataclass_options(node)) is None:
            continue
        bases = tuple(imported.get(base.id, f"{module}.{base.id}") for base in node.bases if isinstance(base, ast.Name))
        found.append(
            DataclassInfo(
                where=f"{label}:{node.lineno} {node.name}",
                module=module,
                name=node.name,
                n_own_fields=sum(_is_field(statement) for statement in node.body),
                kw_only=options.get("kw_only", False),
                frozen=options.get("frozen", False),
                bases=bases,
            )
        )
    return found


def wide_without_kw_only(classes: list[DataclassInfo]) -> list[str]:
    """``where`` and field count of each dataclass with ``WIDE_FIELDS`` or more fields that is not kw_only.

    A dataclass base's fields count (found among ``classes`` by its dotted name; re-exports resolved by name
    alone when that is unambiguous)."""
    by_dotted = {f"{c.module}.{c.name}": c for c in classes}
    by_name: dict[str, list[DataclassInfo]] = {}
    for c in classes:
        by_name.setdefault(c.name, []).append(c)

    def resolve(dotted: str) -> DataclassInfo | None:
        if dotted in by_dotted:
            return by_dotted[dotted]
        same_name = by_name.get(dotted.rsplit(".", 1)[-1], [])
        return same_name[0] if len(same_name) == 1 else None

    def n_fields(c: DataclassInfo, seen: frozenset[str] = frozenset()) -> int:
        bases = [b for b in map(resolve, c.bases) if b is not None and b.where not in seen]
        return c.n_own_fields + sum(n_fields(b, seen | {c.where}) for b in bases)

    return [f"{c.where} ({n} fields)" for c in classes if (n := n_fields(c)) >= WIDE_FIELDS and not c.kw_only]


def _is_dict_of_instance(node: ast.expr) -> bool:
    """``x.__dict__`` or ``vars(x)``."""
    if isinstance(node, ast.Attribute):
        return node.attr == "__dict__"
    return isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "vars" and bool(node.args)


def frozen_bypasses(source: str, label: str) -> list[str]:
    """``label:line`` and the code of each write that goes around a frozen dataclass's ``__setattr__``."""
    found = []
    for node in ast.walk(ast.parse(source, filename=label)):
        if not isinstance(node, ast.stmt | ast.expr):
            continue
        breach = False
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
            owner, attribute = node.func.value, node.func.attr
            around_setattr = attribute in BYPASS_ATTRIBUTES and (
                (isinstance(owner, ast.Name) and owner.id == "object")
                or (isinstance(owner, ast.Call) and isinstance(owner.func, ast.Name) and owner.func.id == "super")
            )
            breach = around_setattr or (attribute in DICT_WRITES and _is_dict_of_instance(owner))
        elif isinstance(node, ast.Assign | ast.AugAssign | ast.AnnAssign | ast.Delete):
            targets = node.targets if isinstance(node, ast.Assign | ast.Delete) else [node.target]
            for target in targets:
                breach |= isinstance(target, ast.Subscript) and _is_dict_of_instance(target.value)
                breach |= isinstance(target, ast.Attribute) and target.attr == "__dict__"
        if breach:
            found.append(f"{label}:{node.lineno} {ast.unparse(node)}")
    return found


def _modules() -> list[tuple[Path, str, str]]:
    """(path, dotted module name, label) of every module of the packages."""
    out = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            parts = path.relative_to(ROOT).with_suffix("").parts
            module = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            out.append((path, module, str(path.relative_to(ROOT))))
    return out


# The scanners on small sources: each rule's breach is found, and what keeps the rule is not.

WIDE_SOURCE = """
from dataclasses import KW_ONLY, dataclass, field
from typing import ClassVar
import dataclasses

@dataclass(frozen=True)
class Wide:
    a: int
    b: int
    c: int
    d: int
    e: int
    f: int
    g: int
    h: int = 0

@dataclasses.dataclass(frozen=True, kw_only=True)
class WideKeyword:
    a: int
    b: int
    c: int
    d: int
    e: int
    f: int
    g: int
    h: int = field(default=0)

@dataclass
class Narrow:
    a: int
    b: int
    c: int
    d: int
    e: int
    f: int
    g: int
    LIMIT: ClassVar[int] = 3
    _: KW_ONLY

@dataclass
class Base:
    a: int
    b: int
    c: int
    d: int

@dataclass
class Derived(Base):
    e: int
    f: int
    g: int
    h: int
"""

BYPASS_SOURCE = """
class Frozen:
    def __post_init__(self):
        object.__setattr__(self, "cache", 1)
        super().__setattr__("other", 2)
        self.__dict__["more"] = 3
        vars(self).update(more=4)
        self.__dict__.setdefault("more", 5)
        del vars(self)["more"]
"""

CLEAN_SOURCE = """
import dataclasses

def copy(record, **changes):
    values = vars(record)
    setattr(type(record), "label", "x")
    return dataclasses.replace(record, **changes), dict(values), record.__dict__.get("a")
"""


def test_the_width_scan_finds_a_wide_dataclass_without_kw_only() -> None:
    found = wide_without_kw_only(dataclasses_in(WIDE_SOURCE, "pkg.mod", "mod.py"))
    assert found == ["mod.py:7 Wide (8 fields)", "mod.py:48 Derived (8 fields)"]


def test_the_bypass_scan_finds_every_write_around_frozen() -> None:
    found = frozen_bypasses(BYPASS_SOURCE, "mod.py")
    assert sorted(int(line.split()[0].split(":")[1]) for line in found) == list(range(4, 10))
    assert frozen_bypasses(CLEAN_SOURCE, "mod.py") == []


# The package itself.


@pytest.fixture(scope="module")
def package_classes() -> list[DataclassInfo]:
    classes = []
    for path, module, label in _modules():
        classes += dataclasses_in(path.read_text(encoding="utf-8"), module, label)
    return classes


def test_every_wide_dataclass_is_keyword_only(package_classes: list[DataclassInfo]) -> None:
    assert sum(c.n_own_fields >= WIDE_FIELDS for c in package_classes) >= 30  # the scan sees the package's
    assert wide_without_kw_only(package_classes) == []


def test_no_frozen_dataclass_is_written_after_construction(package_classes: list[DataclassInfo]) -> None:
    assert sum(c.frozen for c in package_classes) >= 100  # the scan sees the package's
    found = []
    for path, _, label in _modules():
        found += frozen_bypasses(path.read_text(encoding="utf-8"), label)
    assert found == []
