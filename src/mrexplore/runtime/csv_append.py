"""Append-only CSV files that survive a kill: whole lines in one write, a cut last line dropped on reopen."""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = ["append_row", "drop_partial_tail", "keep_rows"]


def drop_partial_tail(path: Path) -> int:
    """Cut a last line that a kill left half-written (no newline at its end); returns the bytes dropped."""
    if not path.exists():
        return 0
    with open(path, "rb+") as f:
        size = f.seek(0, os.SEEK_END)
        if size == 0:
            return 0
        f.seek(size - 1)
        if f.read(1) == b"\n":
            return 0
        start = max(0, size - (1 << 20))
        f.seek(start)
        tail = f.read()
        keep = start + tail.rfind(b"\n") + 1 if b"\n" in tail else 0
        f.truncate(keep)
        os.fsync(f.fileno())
        return size - keep


def append_row(path: Path, columns: Sequence[str], row: dict[str, Any]) -> None:
    """Append ``row`` (None as empty) with one write of its whole line, synced; a new file gets the header
    first, written atomically."""
    if not path.exists() or path.stat().st_size == 0:
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text(",".join(columns) + "\n")
        tmp.replace(path)
    buf = io.StringIO()
    csv.DictWriter(buf, fieldnames=list(columns), lineterminator="\n").writerow(
        {k: ("" if row.get(k) is None else row[k]) for k in columns}
    )
    fd = os.open(path, os.O_WRONLY | os.O_APPEND)
    try:
        os.write(fd, buf.getvalue().encode())
        os.fsync(fd)
    finally:
        os.close(fd)


def keep_rows(path: Path, n: int) -> None:
    """Keep the header and the first ``n`` data rows (a resumed run drops what it will write again)."""
    if not path.exists():
        return
    lines = path.read_bytes().splitlines(keepends=True)
    if len(lines) > n + 1:
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_bytes(b"".join(lines[: n + 1]))
        tmp.replace(path)
