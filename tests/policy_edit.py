"""Tests' tool: a copy of a policy file with its header or a weight changed (as a hostile or damaged file)."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np


def edited_policy(
    src: Path,
    dst: Path,
    header: Callable[[dict[str, Any]], None] | None = None,
    weights: Callable[[dict[str, np.ndarray]], None] | None = None,
) -> Path:
    """``src`` written to ``dst`` after ``header`` and ``weights`` changed its header and weights in place
    (the digest is left as it was)."""
    with np.load(src, allow_pickle=False) as z:
        head = json.loads(bytes(z["__header__"]).decode())
        state = {k: np.array(z[k]) for k in z.files if k != "__header__"}
    names = {k[2:]: k for k in state}
    plain = {k: state[v] for k, v in names.items()}
    if header is not None:
        header(head)
    if weights is not None:
        weights(plain)
    with Path(dst).open("wb") as f:
        np.savez(
            f, __header__=np.frombuffer(json.dumps(head).encode(), np.uint8), **{"w:" + k: v for k, v in plain.items()}
        )
    return Path(dst)
