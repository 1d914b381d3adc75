"""The layer contract (pyproject's ``[tool.importlinter]``) holds for the package and catches an upward import."""

from __future__ import annotations

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
        [str(LINT), "--config", str(tree / "pyproject.toml"), "--no-cache"],
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
    assert "1 kept, 0 broken" in out.stdout


def test_an_upward_import_breaks_the_contract(tree: Path) -> None:
    # layer 1 reaching up into the mission it serves
    (tree / "src" / "mrexplore" / "preprocessing" / "upward.py").write_text(
        '"""An import against the layers."""\n\nfrom mrexplore.mission import Mission\n\n__all__ = ["Mission"]\n'
    )
    out = _lint(tree)
    assert out.returncode == 1
    assert "mrexplore.preprocessing.upward -> mrexplore.mission" in out.stdout
