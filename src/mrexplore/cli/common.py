"""What every command shares: the one-line-error parser, the few argument types that are no setting, the
checks of output paths and of the team's faults, made before any work starts."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any, NoReturn

from mrexplore.config import RunConfig
from mrexplore.types import MrExploreError

__all__ = [
    "EXIT_BAD_INPUT",
    "EXIT_INTERRUPTED",
    "Parser",
    "xy",
    "floats",
    "number",
    "SEED",
    "COUNT",
    "WORKERS",
    "POSITIVE",
    "LOSS",
    "add_progress",
    "check_output",
    "check_failures",
    "need_torch",
    "int_list",
    "DEFAULT_STRATEGY",
    "POLICY_HELP",
    "PREDICTOR_HELP",
]

EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 130
DEFAULT_STRATEGY = "hier-plan-nolocal"
"""The learned global cost under the team plan's, no local layer: it took fewer steps than ``hier`` on the
training's validation maps with 2, 3 and 8 robots and loses to it in no dev-set class (docs/learned.md)."""
POLICY_HELP = (
    "weights of the learned strategies (hier, ncm), written by 'mrexplore train': FILE, or KIND=FILE pairs "
    "(hier=A.npz,ncm=B.npz) where a run has both (default: the shipped policies)"
)
PREDICTOR_HELP = (
    "map predictor of the predictive strategies (hier-predict-heuristic, hier-predict): FILE written by "
    "'mrexplore train --target predictor', or none (every unknown cell free); default: the shipped one"
)
TORCH_MISSING = (
    "training needs torch, which is not installed: pip install 'mrexplore[train]' (on a machine without an "
    "NVIDIA GPU, first: pip install torch --index-url https://download.pytorch.org/whl/cpu)"
)


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors (no usage block), exit code 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_BAD_INPUT, f"mrexplore: error: {message}; see '{self.prog} --help'\n")


def xy(text: str) -> tuple[float, float]:
    """An argparse type: ``X,Y`` in metres, both finite."""
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be X,Y in metres, got {text!r}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise argparse.ArgumentTypeError(f"must be finite X,Y in metres, got {text!r}")
    return (x, y)


def floats(count: int, what: str) -> Any:
    """An argparse type: ``count`` comma-separated finite numbers."""

    def parse(text: str) -> tuple[float, ...]:
        try:
            values = tuple(float(v) for v in text.split(","))
        except ValueError:
            values = ()
        if len(values) != count or not all(math.isfinite(v) for v in values):
            raise argparse.ArgumentTypeError(f"must be {what}, got {text!r}")
        return values

    return parse


def number(low: float, rule: str, *, integer: bool = False, below: float | None = None) -> Any:
    """An argparse type: a finite number >= ``low`` (and < ``below``), named ``rule`` in its error."""

    def parse(text: str) -> float | int:
        try:
            value: float | int = int(text) if integer else float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {rule}, got {text!r}") from None
        if not math.isfinite(value) or value < low or (below is not None and value >= below):
            raise argparse.ArgumentTypeError(f"must be {rule}, got {text!r}")
        return value

    return parse


POSITIVE = number(1e-300, "a number > 0")
NON_NEGATIVE = number(0, "a number >= 0")
SEED = number(0, "an integer >= 0", integer=True)
COUNT = number(1, "an integer >= 1", integer=True)
WORKERS = number(1, "an integer >= 1 (leave the flag out for one per core)", integer=True)
LOSS = number(0, "a probability in [0, 1)", below=1)


def int_list(text: str, name: str) -> list[int]:
    """Comma-separated integers, at least one; one line naming ``name`` otherwise."""
    try:
        values = [int(v) for v in text.split(",") if v]
    except ValueError:
        raise MrExploreError(f"{name} must be comma-separated integers, got {text!r}") from None
    if not values:
        raise MrExploreError(f"{name} must name at least one value, got {text!r}")
    return values


def add_progress(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--progress",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="--progress: a bar; --no-progress: nothing (default: a bar on a terminal, else a line every 5 s)",
    )


def check_failures(run: RunConfig, n: int) -> None:
    """Refuse, before any work, a robot failure of a robot outside a team of ``n``."""
    for robot, _ in run.mission.faults.robot_failures:
        if robot >= n:
            raise MrExploreError(f"--robot-failure names robot {robot}, but a team of {n} has robots 0..{n - 1}")


def check_output(path: str | None, flag: str, folder: bool = False) -> None:
    """Refuse, before any work, an output path that cannot be written: a file is created there and removed
    again (an existing file is opened for appending, not changed); a folder must take a new file."""
    if path is None:
        return
    p = Path(path)
    if folder:
        if p.exists() and not p.is_dir():
            raise MrExploreError(f"{flag} {p} is a file, not a folder; pass a folder")
        parent = p if p.exists() else next((q for q in p.parents if q.exists()), Path("."))
        _try_writing(flag, p, parent, None)
        return
    if p.is_dir():
        raise MrExploreError(f"{flag} {p} is a folder; pass a file path")
    if not p.parent.is_dir():
        raise MrExploreError(f"{flag} folder {p.parent} does not exist; create it first")
    _try_writing(flag, p, p.parent, p)


def _try_writing(flag: str, p: Path, parent: Path, target: Path | None) -> None:
    """Create ``target`` (or a temporary file in ``parent``) and remove it; one line naming why it failed."""
    import errno
    import tempfile

    try:
        if target is None:
            with tempfile.TemporaryFile(dir=parent):
                pass
        elif target.exists():
            with open(target, "ab"):
                pass
        else:
            with open(target, "xb"):
                pass
            target.unlink()
    except OSError as exc:
        why = {
            errno.EACCES: f"permission denied in {parent}",
            errno.EPERM: f"permission denied in {parent}",
            errno.EROFS: f"{parent} is on a read-only file system",
            errno.ENOENT: f"{parent} takes no new files",
            errno.ENOSPC: f"no space left in {parent}",
        }.get(exc.errno or 0, exc.strerror or type(exc).__name__)
        raise MrExploreError(f"{flag} {p} cannot be written ({why}); choose a writable path") from None


def need_torch() -> None:
    """One line naming the fix where torch cannot be imported (the commands that train need it)."""
    import importlib.util

    try:
        found = importlib.util.find_spec("torch") is not None
    except (ImportError, ValueError):  # an import hook that refuses it, or a torch module without a spec
        found = False
    if not found:
        raise MrExploreError(TORCH_MISSING)
