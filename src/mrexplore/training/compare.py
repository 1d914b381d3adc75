"""Policy files side by side on maps no dev set holds, with the heuristic (``mrexplore report policies``):
how two training runs are compared without reading the dev maps."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from mrexplore.bench.report import paired_bootstrap
from mrexplore.config import TrainConfig
from mrexplore.training.episodes import FRESH_SEED0
from mrexplore.training.search import relative_score
from mrexplore.training.trainer import validate_policy
from mrexplore.types import MrExploreError

__all__ = ["compare_policies"]


def compare_policies(
    policies: Sequence[Path], train_dir: Path | None, fresh: int, robots: int | None, workers: int
) -> tuple[list[str], list[dict[str, object]]]:
    """The heuristic (``hier-heuristic``) and each policy, deterministic decoding at 0.1 m, on the maps
    ``mrexplore train`` validates on (64: half held-out training DungeonMaps, half ``varied:`` plans of
    validation seeds) or, with ``fresh`` N, on N ``varied:`` plans of seeds no run trains or validates on.

    Returns a line per policy (mean steps to the end and to 99%, coverage, the ``relative`` score against
    the heuristic, and fewer steps than the first policy, % with a 95% paired bootstrap interval) and a row
    per map and policy (steps, steps to 99%, coverage).
    """
    for p in policies:
        if not p.is_file():
            raise MrExploreError(f"policy file not found: {p}; pass a policy.npz that mrexplore train wrote")
    if fresh < 0:
        raise MrExploreError(f"--fresh must be >= 0, got {fresh}; pass a count of plans, or 0 for validation")
    cfg = TrainConfig() if robots is None else TrainConfig(val_robots=robots)
    plans = [f"{cfg.episodes.plans}:{FRESH_SEED0 + i}" for i in range(fresh)] or None
    maps, ref, ref_cov = validate_policy(None, cfg, train_dir, workers, plans)
    lines = [
        f"{len(maps)} {'fresh' if plans else 'validation'} maps, {cfg.val_robots} robots, {cfg.episodes.resolution_m} m"
    ]
    first: np.ndarray | None = None
    per_map: list[dict[str, object]] = []
    for name, policy in [("hier-heuristic", None), *[(str(p), p) for p in policies]]:
        steps, cov = (ref, ref_cov) if policy is None else validate_policy(policy, cfg, train_dir, workers, plans)[1:]
        per_map += [
            {"policy": name, "map": m, "steps": int(a), "steps_99": int(b), "coverage": float(c)}
            for m, a, b, c in zip(maps, steps[0], steps[1], cov, strict=True)
        ]
        score = float(relative_score(steps[0], steps[1], ref[0], ref[1]))
        line = (
            f"{name}: {steps[0].mean():.1f} steps, {steps[1].mean():.1f} to 99%, "
            f"coverage {cov.mean():.4f}, relative score {score:.4f}"
        )
        if policy is not None and first is None:
            first = steps
        elif policy is not None and first is not None:
            (e0, l0, h0), (e1, l1, h1) = (paired_bootstrap(list(steps[k]), list(first[k])) for k in (0, 1))
            line += f"; fewer steps than the first: {e0:+.1f}% [{l0:+.1f}, {h0:+.1f}] end,"
            line += f" {e1:+.1f}% [{l1:+.1f}, {h1:+.1f}] to 99%"
        lines.append(line)
    return lines, per_map
