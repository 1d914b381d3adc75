"""The learned methods, each described once: the hier policy (the paper's mGNN residual), NeuralCoMapping's
policy and the map predictor. A description says what the rest of the package asks of a method (its file
format, its shipped weights, its NumPy loader, what its untrained start decides as, how it is validated),
so that no module tests a method's name: the command line, the strategies, the bench and the trainer look
the method up here. Their torch twins (networks, updates, stages) are training's
(:mod:`mrexplore.training.methods`).

Examples
--------
>>> learned_method("ncm").validates_sampled, learned_method("hier").validates_sampled
(True, False)
>>> learned_method("hier").default_weights().name
'policy.npz'
>>> sorted(LEARNED_METHODS)
['hier', 'ncm', 'predictor']
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from mrexplore.config import LearnedConfig
from mrexplore.global_planning.learned.policy_file import (
    HIER_FORMAT,
    NCM_FORMAT,
    default_ncm_policy_path,
    default_policy_path,
    hier_config,
    load_ncm_policy_np,
    load_policy_np,
    read_policy_file,
)
from mrexplore.prediction.network import PREDICTOR_FORMAT, default_predictor_path, load_predictor
from mrexplore.types import MrExploreError

__all__ = ["LearnedMethod", "LEARNED_METHODS", "register_learned_method", "learned_method"]


def _never(cfg: LearnedConfig) -> bool:
    return False


@dataclass(frozen=True)
class LearnedMethod:
    """What the package asks of one learned method."""

    kind: str
    """Its name: a policy kind (``--policy KIND=FILE``, ``train.strategy``), or ``predictor``."""
    file_format: str
    """The format tag its files carry."""
    default_weights: Callable[[], Path]
    """The weights shipped in the package."""
    load: Callable[[Path | None], Any]
    """Its NumPy loader (None: the shipped weights): a network that needs no torch, with what a record says
    of its file."""
    untrained_start: str
    """What the method decides as before any training (the yardstick of its training's validation)."""
    starts_from_heuristic: bool = False
    """The untrained start is a heuristic that needs no weights (hier's residual starts at zero)."""
    validates_sampled: bool = False
    """Its own evaluation samples each robot's choice: training validates that decoding too (NCM's)."""
    reads_prediction: Callable[[LearnedConfig], bool] = _never
    """Whether a network of these settings reads the map predictor's completion of the belief."""

    def file_reads_prediction(self, path: Path | None) -> bool:
        """Whether the policy file at ``path`` (None: the shipped one) reads a prediction; False where it
        cannot be read (whoever loads it refuses it then)."""
        if self.reads_prediction is _never:
            return False
        try:
            return self.reads_prediction(hier_config(read_policy_file(path, self.file_format))[0])
        except (MrExploreError, KeyError, TypeError, ValueError):
            return False


LEARNED_METHODS: dict[str, LearnedMethod] = {}


def register_learned_method(method: LearnedMethod) -> None:
    """Describe a learned method once, by its kind."""
    if method.kind in LEARNED_METHODS:
        raise MrExploreError(f"learned method {method.kind!r} is described already; give it another kind")
    LEARNED_METHODS[method.kind] = method


def learned_method(kind: str) -> LearnedMethod:
    """The description of learned method ``kind``; one line listing the kinds where there is none."""
    method = LEARNED_METHODS.get(kind)
    if method is None:
        raise MrExploreError(f"no learned method {kind!r}; choose one of {', '.join(LEARNED_METHODS)}")
    return method


register_learned_method(
    LearnedMethod(
        "hier",
        HIER_FORMAT,
        default_policy_path,
        load_policy_np,
        "hier-heuristic's cost",
        starts_from_heuristic=True,
        reads_prediction=lambda cfg: cfg.reads_prediction,
    )
)
register_learned_method(
    LearnedMethod(
        "ncm", NCM_FORMAT, default_ncm_policy_path, load_ncm_policy_np, "an untrained network", validates_sampled=True
    )
)
register_learned_method(
    LearnedMethod("predictor", PREDICTOR_FORMAT, default_predictor_path, load_predictor, "every unknown cell free")
)
