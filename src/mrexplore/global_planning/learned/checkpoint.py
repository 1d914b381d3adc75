"""Saving policies from the torch networks and loading them into torch (training); deciding needs neither
(:mod:`~mrexplore.global_planning.learned.policy_file` loads the NumPy networks)."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import torch

from mrexplore.config import config_to_dict
from mrexplore.global_planning.learned.ncm_network import NcmNet
from mrexplore.global_planning.learned.network import MultiGraphNet
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
    pf = read_policy_file(path, HIER_FORMAT)

    def build() -> MultiGraphNet:
        net = MultiGraphNet(*hier_config(pf))
        _with_weights(net, pf.state)
        return net

    return built(pf, build)


def load_ncm_policy(path: Path | None = None) -> LoadedNcmPolicy:
    """Load an ``ncm`` policy written by :func:`save_policy` (default: the shipped one) into torch; one-line
    errors."""
    pf = read_policy_file(path, NCM_FORMAT)

    def build() -> NcmNet:
        net = NcmNet(ncm_config(pf))
        _with_weights(net, pf.state)
        return net

    return built(pf, build)
