"""Weight files without torch, shared by policies and the map predictor: NumPy archives of float32 weights
with a JSON header, their digest, the file's sha256 and the code version that wrote them."""

from __future__ import annotations

import hashlib
import json
import subprocess
from collections.abc import Mapping
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["code_version", "file_sha256", "weights_digest", "write_weights_archive", "HEADER_MEMBER", "WEIGHT_PREFIX"]

HEADER_MEMBER = "__header__"
"""Name of the JSON header inside the archive (the weights are the other members)."""
WEIGHT_PREFIX = "w:"
"""Prefix of a weight's name inside the archive."""


def file_sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def code_version() -> str:
    """The package version, with the git commit where the source is a checkout."""
    try:
        version = metadata.version("mrexplore")
    except metadata.PackageNotFoundError:
        version = "unknown"
    try:
        sha = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            cwd=Path(__file__).parent,
            capture_output=True,
            text=True,
            timeout=5,
            check=False,
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        sha = ""
    return f"{version}+{sha}" if sha else version


def weights_digest(state: Mapping[str, Any]) -> str:
    """sha256 over the weights (names, shapes and float32 bytes, in name order): a file whose weights were
    changed after saving no longer matches. Arrays or torch tensors; both give the same digest.

    Examples
    --------
    >>> weights_digest({"b": np.zeros(2), "a": np.ones((1, 1))}) == weights_digest({"a": [[1.0]], "b": [0.0, 0.0]})
    True
    """
    h = hashlib.sha256()
    for name in sorted(state):
        v = state[name]
        if hasattr(v, "detach"):  # a torch tensor
            v = v.detach().float().contiguous().cpu().numpy()
        a = np.array(v, dtype=np.float32, order="C")  # ascontiguousarray would make a 0-d array 1-d
        h.update(f"{name}{tuple(a.shape)}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def write_weights_archive(path: Path, header: Mapping[str, Any], state: Mapping[str, Any]) -> None:
    """Write ``state`` (arrays or tensors, stored as float32) under ``header`` (plain JSON data, with a
    ``format`` tag), adding the weights digest and the code version (where ``header`` has none); atomic (a
    kill never leaves half a file)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    arrays = {}
    for k, v in state.items():
        if hasattr(v, "detach"):
            v = v.detach().float().contiguous().cpu().numpy()
        arrays[WEIGHT_PREFIX + k] = np.array(v, dtype=np.float32, order="C")
    full = {"code_version": code_version(), "meta": {}, **header, "weights_sha256": weights_digest(state)}
    text = json.dumps(full, sort_keys=True, allow_nan=False, default=_plain)
    tmp = path.with_name(path.name + ".tmp")
    with tmp.open("wb") as f:
        payload: dict[str, Any] = {HEADER_MEMBER: np.frombuffer(text.encode(), np.uint8), **arrays}
        np.savez(f, **payload)
    tmp.replace(path)


def _plain(value: Any) -> Any:
    """JSON form of NumPy scalars and arrays in a header."""
    if isinstance(value, np.generic | np.ndarray):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not plain data")
