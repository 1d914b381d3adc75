"""Saving policies from the torch networks and loading them into torch (training); deciding needs neither
(:mod:`~mrexplore.global_planning.learned.policy_file` loads the NumPy networks)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import torch

from mrexplore.config import config_to_dict
from mrexplore.global_planning.learned.policy_file import (
    HIER_FORMAT,
    MAX_POLICY_BYTES,
    NCM_FORMAT,
    VALUE_INPUTS,
    LoadedPolicy,
    built,
    code_version,
    default_ncm_policy_path,
    default_policy_path,
    file_sha256,
    hier_config,
    ncm_config,
    read_policy_file,
    weights_digest,
    write_policy_file,
)
from mrexplore.training.hier_net import MultiGraphNet
from mrexplore.training.ncm_net import NcmNet
from mrexplore.types import MrExploreError

__all__ = [
    "save_policy",
    "load_policy",
    "load_ncm_policy",
    "default_ncm_policy_path",
    "LoadedNcmPolicy",
    "weights_digest",
    "default_policy_path",
    "file_sha256",
    "code_version",
    "LoadedPolicy",
    "MAX_POLICY_BYTES",
    "VALUE_INPUTS",
]

LoadedNcmPolicy = LoadedPolicy[NcmNet]


def save_policy(path: Path, net: MultiGraphNet | NcmNet, meta: dict[str, Any] | None = None) -> None:
    """Write the weights (float32), the network's config, the code version and ``meta`` (plain data): a
    ``hier`` policy for a :class:`MultiGraphNet`, an ``ncm`` one (the actor alone) for an :class:`NcmNet`."""
    head: dict[str, Any] = (
        {"format": NCM_FORMAT, "ncm_config": dataclasses.asdict(net.cfg)}
        if isinstance(net, NcmNet)
        else {"format": HIER_FORMAT, "learned_config": config_to_dict(net.cfg), "value_inputs": net.value_inputs}
    )
    write_policy_file(path, {**head, "meta": meta or {}}, net.state_dict())


def _with_weights(net: torch.nn.Module, state: dict[str, Any]) -> None:
    net.load_state_dict({k: torch.from_numpy(v.copy()) for k, v in state.items()})
    net.eval()


def load_policy(path: Path | None = None) -> LoadedPolicy[MultiGraphNet]:
    """Load a ``hier`` policy written by :func:`save_policy` (default: the shipped one) into torch; one-line
    errors."""
    pf = read_policy_file(path, HIER_FORMAT, _read_torch)

    def build() -> MultiGraphNet:
        net = MultiGraphNet(*hier_config(pf))
        _with_weights(net, pf.state)
        return net

    return built(pf, build)


def load_ncm_policy(path: Path | None = None) -> LoadedNcmPolicy:
    """Load an ``ncm`` policy written by :func:`save_policy` (default: the shipped one) into torch; one-line
    errors."""
    pf = read_policy_file(path, NCM_FORMAT, _read_torch)

    def build() -> NcmNet:
        net = NcmNet(ncm_config(pf))
        _with_weights(net, pf.state)
        return net

    return built(pf, build)


def _read_torch(path: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    """Header and weights of a policy in torch's archive format, as older versions wrote them."""
    try:
        blob = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # noqa: BLE001 - torch raises many kinds for a file that is not a checkpoint
        raise MrExploreError(
            f"policy file {path} is not a mrexplore policy ({type(exc).__name__}); retrain it"
        ) from None
    if not isinstance(blob, dict) or not isinstance(blob.get("state_dict"), dict):
        raise MrExploreError(f"policy file {path} is not a mrexplore policy (no format tag); retrain it")
    raw = blob["state_dict"]
    if not all(isinstance(v, torch.Tensor) for v in raw.values()):
        raise MrExploreError(f"policy file {path} is not a mrexplore policy (its weights are no tensors); retrain it")
    state = {k: v.detach().float().contiguous().numpy() for k, v in raw.items()}
    header = {k: v for k, v in blob.items() if k != "state_dict"}
    return header, state
