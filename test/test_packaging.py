"""Released installs: the wheel holds every module, an installed copy imports, every import is declared."""

from __future__ import annotations

import ast
import email
import importlib.metadata
import json
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("bsp_ros", "msg_adapters")

# Each third-party module the package imports: (the pip requirement that provides it, or None where pip
# cannot, and the package.xml key that provides it on a Jazzy cell, or None where rosdep has no key).
DECLARED: dict[str, tuple[str | None, str | None]] = {
    "numpy": ("numpy", "python3-numpy"),
    "scipy": ("scipy", "python3-scipy"),
    "yaml": ("pyyaml", "python3-yaml"),
    "matplotlib": ("matplotlib", "python3-matplotlib"),
    "rosbags": ("rosbags", "python3-rosbags-pip"),
    "mcap": ("mcap", "mcap-ros2-support"),
    "mcap_ros2": ("mcap-ros2-support", "mcap-ros2-support"),
    "lz4": ("lz4", "mcap-ros2-support"),
    "zstandard": ("zstandard", "mcap-ros2-support"),
    # One BLAS thread per node (bsp_ros.live.runtime.threads); rosdep has no key for it, and a node without it
    # keeps BLAS's default threads.
    "threadpoolctl": ("threadpoolctl", None),
    # The optional PostgreSQL store (extra `postgres`); rosdep has no key for psycopg 3.
    "psycopg": ("psycopg", None),
    # Only bsp_ros.to_frame, for a user who has it; not a dependency (to_records needs nothing).
    "pandas": (None, None),
    "rclpy": ("ros-jazzy-rclpy", "rclpy"),
    "rcl_interfaces": ("ros-jazzy-rclpy", "rcl_interfaces"),
    "builtin_interfaces": ("ros-jazzy-rclpy", "rcl_interfaces"),
    "geometry_msgs": ("ros-jazzy-geometry-msgs", "geometry_msgs"),
    "sensor_msgs": ("ros-jazzy-sensor-msgs", "sensor_msgs"),
    "std_msgs": ("ros-jazzy-std-msgs", "std_msgs"),
    "diagnostic_msgs": ("ros-jazzy-diagnostic-msgs", "diagnostic_msgs"),
    "nav_msgs": ("ros-jazzy-nav-msgs", "nav_msgs"),
    "trajectory_msgs": ("ros-jazzy-trajectory-msgs", "trajectory_msgs"),
    "std_srvs": ("ros-jazzy-std-srvs", "std_srvs"),
    # Not on PyPI: on a cell from apt; elsewhere the nodes take the sensor rotation from a parameter.
    "tf2_msgs": (None, "tf2_msgs"),
}


def _source_modules() -> set[str]:
    modules = set()
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            parts = path.relative_to(ROOT).with_suffix("").parts
            modules.add(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return modules


def _third_party_imports() -> set[str]:
    names: set[str] = set()
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(), str(path))):
                if isinstance(node, ast.Import):
                    names.update(alias.name.split(".")[0] for alias in node.names)
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names.add(node.module.split(".")[0])
    return {n for n in names if n not in sys.stdlib_module_names and n not in PACKAGES}


def _requirement_name(spec: str) -> str:
    return re.split(r"[\s\[<>=!~;]", spec.strip(), maxsplit=1)[0].lower().replace("_", "-")


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel `pip wheel . --no-deps` builds from the source tree (a copy: the build writes into it)."""
    source = tmp_path_factory.mktemp("source")
    ignore = shutil.ignore_patterns(".git", "build", "install", "log", "*.egg-info", "__pycache__", "bags")
    shutil.copytree(ROOT, source / "bsp_ros", ignore=ignore)
    out = tmp_path_factory.mktemp("wheel")
    command = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(out), str(source / "bsp_ros")]
    done = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    (path,) = out.glob("bsp_ros-*.whl")
    return path


def test_every_source_directory_is_a_package() -> None:
    missing = [
        str(d.relative_to(ROOT))
        for package in PACKAGES
        for d in [ROOT / package, *(ROOT / package).rglob("*")]
        if d.is_dir() and any(d.glob("*.py")) and not (d / "__init__.py").exists()
    ]
    assert missing == []


def test_wheel_holds_every_module_and_the_default_config(wheel: Path) -> None:
    names = set(zipfile.ZipFile(wheel).namelist())
    in_wheel = {n[:-3].replace("/", ".").removesuffix(".__init__") for n in names if n.endswith(".py")}
    assert _source_modules() - in_wheel == set()
    assert "bsp_ros/config/bsp_cell.yaml" in names


def test_installed_wheel_imports_every_module(wheel: Path, tmp_path: Path) -> None:
    target = tmp_path / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--target", str(target), str(wheel)],
        check=True,
        capture_output=True,
        timeout=300,
    )
    script = (
        "import importlib, sys\n"
        # __main__ modules run the command when imported: the wheel test above covers their presence.
        f"for name in {sorted(m for m in _source_modules() if not m.endswith('__main__'))!r}:\n"
        "    module = importlib.import_module(name)\n"
        f"    assert module.__file__.startswith({str(target)!r}), (name, module.__file__)\n"
        "print('ok')\n"
    )
    env = {**os.environ, "PYTHONPATH": str(target)}
    # Run from an empty directory so that the source tree cannot shadow the installed copy.
    done = subprocess.run(
        [sys.executable, "-c", script], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr[-2000:]
    # `python -c "import bsp_ros; bsp_ros.identify(BAG)"` from the installed copy, on a short simulated session.
    import bsp_ros

    bag = bsp_ros.simulate(tmp_path / "short", duration_s=20, seed=3)
    line = (
        f"import bsp_ros; e = bsp_ros.identify({str(bag)!r}); "
        f"assert bsp_ros.api.__file__.startswith({str(target)!r}), bsp_ros.api.__file__; "
        "q = e.quantity('static_moment_kgm', 'forearm'); print(e.valid, q.value, q.std)"
    )
    done = subprocess.run(
        [sys.executable, "-c", line], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr[-2000:]
    valid, value, std = done.stdout.split()
    truth = json.loads((bag / "truth.json").read_text())["segments"]["forearm"]["static_moment_kgm"]
    assert valid == "True" and abs(float(value) - truth) < 3 * float(std)


def test_every_import_is_listed() -> None:
    assert _third_party_imports() - set(DECLARED) == set()


def test_every_import_is_a_declared_requirement(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as archive:
        (meta,) = [n for n in archive.namelist() if n.endswith(".dist-info/METADATA")]
        metadata = email.message_from_bytes(archive.read(meta))
    declared = {_requirement_name(spec) for spec in metadata.get_all("Requires-Dist") or []}
    for module in _third_party_imports():
        requirement, _ = DECLARED[module]
        assert requirement is None or requirement in declared, (module, requirement)


def test_every_import_comes_from_its_requirement_here() -> None:
    """The table above is right: the installed requirement (or what it pulls in) provides the module."""
    provided_by = importlib.metadata.packages_distributions()

    def closure(name: str) -> set[str]:
        seen, todo = set(), [name]
        while todo:
            current = todo.pop()
            if current in seen:
                continue
            seen.add(current)
            try:
                requires = importlib.metadata.requires(current) or []
            except importlib.metadata.PackageNotFoundError:
                continue
            todo += [_requirement_name(r) for r in requires if "extra ==" not in r or "fastrtps" in r]
        return seen

    for module in sorted(_third_party_imports()):
        requirement, _ = DECLARED[module]
        if requirement is None or module not in provided_by:
            continue  # not installable from PyPI, or not installed here (an optional extra)
        distributions = {_requirement_name(d) for d in provided_by[module]}
        assert distributions & closure(requirement), (module, requirement, distributions)


def _package_xml_keys() -> set[str]:
    root = ET.parse(ROOT / "package.xml").getroot()
    return {e.text.strip() for tag in ("depend", "exec_depend") for e in root.iter(tag) if e.text}


def test_every_import_has_a_package_xml_key() -> None:
    keys = _package_xml_keys()
    for module in _third_party_imports():
        _, key = DECLARED[module]
        assert key is None or key in keys, (module, key)


def test_package_xml_keys_resolve_for_jazzy_on_noble() -> None:
    """Against rosdep's own lists, as recorded by scripts/check_rosdep_keys.py from a rosdistro checkout."""
    snapshot = yaml.safe_load((ROOT / "test" / "data" / "rosdep_keys_noble.yaml").read_text())
    root = ET.parse(ROOT / "package.xml").getroot()
    every = {e.text.strip() for e in root.iter() if e.tag.endswith("depend") and e.text}
    assert every - set(snapshot["keys"]) == set()


def test_colcon_build_installs_nodes_that_import(tmp_path: Path) -> None:
    """A plain (not symlinked) colcon build of a workspace holding the package, as on a Jazzy cell."""
    colcon = shutil.which("colcon") or str(Path(sys.executable).with_name("colcon"))
    assert Path(colcon).exists(), "colcon is part of the test extra"
    ignore = shutil.ignore_patterns(".git", "build", "install", "log", "*.egg-info", "__pycache__", "bags")
    shutil.copytree(ROOT, tmp_path / "src" / "bsp_ros", ignore=ignore)
    built = subprocess.run(
        [colcon, "build", "--event-handlers", "console_direct-"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert built.returncode == 0, built.stdout[-2000:] + built.stderr[-2000:]
    prefix = tmp_path / "install" / "bsp_ros"
    (site,) = prefix.glob("lib/python3*/site-packages")
    for name in ("bsp", "cell_simulator", "joint_angle_estimator", "bsp_identifier", "session_recorder"):
        assert (prefix / "lib" / "bsp_ros" / name).is_file(), name
    assert (prefix / "share" / "bsp_ros" / "launch" / "bsp_cell.launch.py").is_file()
    assert (prefix / "share" / "bsp_ros" / "config" / "bsp_cell.yaml").is_file()
    assert (prefix / "share" / "ament_index" / "resource_index" / "packages" / "bsp_ros").is_file()
    nodes = ["bsp_ros.live.nodes." + n for n in ("cell_simulator", "joint_angle_estimator", "bsp_identifier")]
    script = (
        "import importlib\n"
        f"for name in {[*nodes, 'bsp_ros.live.nodes.session_recorder', 'bsp_ros.cli']!r}:\n"
        "    module = importlib.import_module(name)\n"
        f"    assert module.__file__.startswith({str(site)!r}), (name, module.__file__)\n"
        "    assert callable(module.main), name\n"
    )
    env = {**os.environ, "PYTHONPATH": str(site)}
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    version = subprocess.run(
        [str(prefix / "lib" / "bsp_ros" / "bsp"), "--version"], cwd=tmp_path, env=env, capture_output=True, text=True
    )
    assert version.stdout.strip() == "bsp_ros 0.1.0", version.stderr[-2000:]
