"""The scaffold of a training run, shared by the policy's and the map predictor's trainers: its folder (a new
run refuses one that holds a run, a resume needs one), its time budget, its checkpoint written atomically, its
CSV log cut back to the rows of the last checkpoint, and the kept weights copied to their final name."""

from __future__ import annotations

import math
import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import torch

from mrexplore.runtime.csv_append import drop_partial_tail, keep_rows
from mrexplore.types import MrExploreError

__all__ = ["RunFolder"]


class RunFolder:
    """One training run's folder ``out``, its clock and its checkpoint ``state.pt``.

    Examples
    --------
    >>> import tempfile
    >>> tmp = tempfile.TemporaryDirectory()
    >>> run = RunFolder(Path(tmp.name) / "run", resume=False, minutes=None)
    >>> run.save_state({"epoch": 3})
    >>> RunFolder(run.out, resume=True, minutes=None).load_state()
    {'epoch': 3}
    >>> tmp.cleanup()
    """

    def __init__(
        self, out: Path, resume: bool, minutes: float | None, say: Callable[[str], None] = lambda s: None
    ) -> None:
        self.out = Path(out)
        self.state_path = self.out / "state.pt"
        if self.state_path.exists() and not resume:
            raise MrExploreError(
                f"{self.out} already holds a training run; pass --resume to continue it, or another --out"
            )
        if resume and not self.state_path.exists():
            raise MrExploreError(f"nothing to resume in {self.out} (no state.pt); drop --resume to start a run there")
        self.out.mkdir(parents=True, exist_ok=True)
        self.resume, self.minutes, self.say = resume, minutes, say
        self.t_start = time.perf_counter()
        self.deadline = math.inf

    def start_clock(self, elapsed_s: float) -> None:
        """Start the budget's clock, ``elapsed_s`` already spent (a resumed run's)."""
        self.t_start = time.perf_counter() - elapsed_s
        self.deadline = self.t_start + self.minutes * 60 if self.minutes is not None else math.inf

    @property
    def elapsed_s(self) -> float:
        """Seconds of the run so far, a resumed run's earlier ones included."""
        return time.perf_counter() - self.t_start

    def load_state(self) -> dict[str, Any]:
        """The checkpoint a resume continues from."""
        blob: dict[str, Any] = torch.load(self.state_path, weights_only=True)
        return blob

    def save_state(self, blob: dict[str, Any]) -> None:
        """Write the checkpoint atomically: a run killed while writing keeps the one before."""
        tmp = self.state_path.with_name("state.pt.tmp")
        torch.save(blob, tmp)
        tmp.replace(self.state_path)

    def log_path(self, rows_kept: int | None) -> Path:
        """``log.csv``, its cut last line dropped and, where given, cut back to ``rows_kept`` rows (those of the
        checkpoint a resume continues from)."""
        path = self.out / "log.csv"
        drop_partial_tail(path)
        if rows_kept is not None:
            keep_rows(path, rows_kept)
        return path

    def keep_best(self, final_name: str, none_kept: str) -> Path:
        """Copy ``best.npz`` (the weights kept on validation) to ``final_name``; ``none_kept`` is the one-line
        error where no stage or epoch wrote it."""
        best = self.out / "best.npz"
        if not best.exists():
            raise MrExploreError(none_kept)
        final = self.out / final_name
        shutil.copyfile(best, final)
        return final
