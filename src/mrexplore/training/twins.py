"""The torch twins of the learned methods (:mod:`mrexplore.global_planning.learned.methods` describes each
method once): the network a training run starts from and the loader of a policy file into torch, by the
method's kind. Deciding never needs them; :func:`decide_with_torch` makes this process's strategies decide on
them, to compare the two (``benchmarks/inference_parity.py``)."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch

from mrexplore.bench.runner import EpisodeSpec, run_episode
from mrexplore.config import TrainConfig
from mrexplore.global_planning.learned.methods import LEARNED_METHODS, learned_method
from mrexplore.training.checkpoint import VALUE_INPUTS, load_ncm_policy, load_policy
from mrexplore.training.hier_net import MultiGraphNet
from mrexplore.training.ncm_net import NcmActorCritic
from mrexplore.types import MrExploreError

__all__ = ["TorchTwin", "TORCH_TWINS", "torch_twin", "decide_with_torch", "episode_deciding_with_torch"]


@dataclass(frozen=True)
class TorchTwin:
    """A learned method's torch side."""

    kind: str
    new_net: Callable[[TrainConfig], MultiGraphNet | NcmActorCritic]
    """The network a training run of these settings starts from (actor and critic together)."""
    load: Callable[[Path | None], Any]
    """A policy file into the torch network (None: the shipped one), which answers the same NumPy scoring
    protocol as the NumPy network."""
    as_trained: Callable[[torch.nn.Module], torch.nn.Module] = lambda net: net
    """A loaded policy's network as a training run holds it (NCM's actor joins a fresh critic)."""


TORCH_TWINS: dict[str, TorchTwin] = {
    "hier": TorchTwin("hier", lambda cfg: MultiGraphNet(cfg.learned, VALUE_INPUTS), load_policy),
    "ncm": TorchTwin("ncm", lambda cfg: NcmActorCritic(), load_ncm_policy, NcmActorCritic.around),
}


def torch_twin(kind: str) -> TorchTwin:
    """The torch twin of learned method ``kind`` (one that training trains)."""
    learned_method(kind)  # an unknown kind: the registry's one-line error
    twin = TORCH_TWINS.get(kind)
    if twin is None:
        raise MrExploreError(
            f"learned method {kind!r} has no torch policy to train here; choose one of {', '.join(TORCH_TWINS)}"
        )
    return twin


def decide_with_torch() -> None:
    """Make this process's learned strategies load their policies into the torch networks (which decide
    through the same protocol), instead of the NumPy ones: a comparison of the two, not a way to deploy."""
    for kind, twin in TORCH_TWINS.items():
        LEARNED_METHODS[kind] = dataclasses.replace(LEARNED_METHODS[kind], load=twin.load)


def episode_deciding_with_torch(spec: EpisodeSpec) -> dict[str, Any]:
    """A bench episode (:func:`~mrexplore.bench.runner.run_episode`) whose learned strategies decide on the
    torch networks: what ``benchmarks/inference_parity.py`` hands the bench's workers."""
    decide_with_torch()
    return run_episode(spec)
