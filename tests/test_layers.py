"""The package's shape: the import contracts (pyproject's ``[tool.importlinter]``) hold and catch an upward or a
forbidden import; the root holds few modules; no function is too long to read, numba kernels aside."""

from __future__ import annotations

import ast
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LINT = Path(sys.executable).with_name("lint-imports")

pytestmark = pytest.mark.skipif(
    not LINT.exists(), reason="import-linter is not installed (pip install -e '.[dev]' brings it)"
)


def _lint(tree: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": str(tree / "src")}
    return subprocess.run(
        [str(LINT), str(tree / "pyproject.toml"), "--no-cache"],
        cwd=tree,
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )


@pytest.fixture()
def tree(tmp_path: Path) -> Path:
    """A copy of the package and its pyproject, to break."""
    shutil.copytree(ROOT / "src" / "mrexplore", tmp_path / "src" / "mrexplore", ignore=shutil.ignore_patterns("*.npz"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    return tmp_path


def test_the_package_keeps_its_layers(tree: Path) -> None:
    out = _lint(tree)
    assert out.returncode == 0, out.stdout + out.stderr
    assert "4 kept, 0 broken" in out.stdout


def test_an_upward_or_a_forbidden_import_breaks_its_contract(tree: Path) -> None:
    """Three imports against the contracts, in one run of the linter: layer 1 reaching up into the mission it
    serves, torch where the strategies decide, rclpy below the ROS 2 adapter."""
    package = tree / "src" / "mrexplore"
    offenders = {
        package / "preprocessing" / "upward.py": 'from mrexplore.mission import Mission\n\n__all__ = ["Mission"]',
        package / "global_planning" / "learned" / "heavy.py": 'import torch\n\n__all__ = ["torch"]',
        package / "mission" / "chatty.py": 'import rclpy\n\n__all__ = ["rclpy"]',
    }
    for path, body in offenders.items():
        path.write_text(f'"""An import against the contracts."""\n\n{body}\n')
    out = _lint(tree)
    assert out.returncode == 1
    assert "mrexplore.preprocessing.upward -> mrexplore.mission" in out.stdout
    assert "mrexplore.global_planning.learned.heavy -> torch" in out.stdout
    assert "mrexplore.mission.chatty -> rclpy" in out.stdout
    assert "1 kept, 3 broken" in out.stdout


PACKAGE = ROOT / "src" / "mrexplore"


def test_the_package_root_holds_at_most_eight_modules() -> None:
    loose = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(loose) <= 8, loose


@pytest.mark.parametrize("package", ["config", "cli"])
def test_no_settings_or_command_line_module_is_above_400_lines(package: str) -> None:
    long = {p.name: n for p in (PACKAGE / package).glob("*.py") if (n := len(p.read_text().splitlines())) > 400}
    assert not long, long


def test_no_ros2_adapter_module_is_above_300_lines() -> None:
    # The ROS 2 modules hold callbacks; the protocol they drive is written once below them (mrexplore.team).
    long = {p.name: n for p in (PACKAGE / "ros2").glob("*.py") if (n := len(p.read_text().splitlines())) > 300}
    assert not long, long


def _is_numba_kernel(node: ast.FunctionDef) -> bool:
    return any("njit" in ast.unparse(d) or "vectorize" in ast.unparse(d) for d in node.decorator_list)


def test_no_function_is_above_100_lines_but_numba_kernels() -> None:
    """A function longer than a screen or two is split; numba kernels, whose loops are the algorithm and whose
    calls cost inside a kernel, are excused."""
    long = []
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and not (
                isinstance(node, ast.FunctionDef) and _is_numba_kernel(node)
            ):
                lines = (node.end_lineno or node.lineno) - node.lineno + 1
                if lines > 100:
                    long.append(f"{path.relative_to(PACKAGE)}:{node.lineno} {node.name} ({lines} lines)")
    assert not long, long


def test_no_module_tests_a_learned_method_by_name_outside_the_registries() -> None:
    """A learned method is described once (global_planning/learned/methods.py, its torch twin in
    training/twins.py and its stages in training/stages.py); elsewhere a method is looked up, never compared
    by name."""
    allowed = {"global_planning/learned/methods.py", "training/twins.py", "training/stages.py", "pipeline/registry.py"}
    tests = []
    for path in PACKAGE.rglob("*.py"):
        rel = path.relative_to(PACKAGE).as_posix()
        for node in ast.walk(ast.parse(path.read_text())):
            if rel not in allowed and isinstance(node, ast.Compare):
                names = [c.value for c in [node.left, *node.comparators] if isinstance(c, ast.Constant)]
                if any(n in ("hier", "ncm", "predictor") for n in names):
                    tests.append(f"{rel}:{node.lineno}")
    assert not tests, tests


def test_no_import_cycle_anywhere_in_the_package() -> None:
    """No module imports, through others, one that imports it (a strongly connected set of modules would
    be one)."""
    grimp = pytest.importorskip("grimp", reason="grimp comes with import-linter (pip install -e '.[dev]')")
    graph = grimp.build_graph("mrexplore", cache_dir=None)
    imports = {m: set(graph.find_modules_directly_imported_by(m)) & graph.modules for m in graph.modules}
    for module in sorted(graph.modules):
        seen, todo = set(), list(imports[module])
        while todo:
            m = todo.pop()
            if m == module:
                raise AssertionError(f"{module} imports itself through {sorted(seen)[:5]}")
            if m not in seen:
                seen.add(m)
                todo.extend(imports[m])
