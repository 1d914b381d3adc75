"""Saving and loading policies: weights, the resolved configs and the code version, with clear errors."""

from __future__ import annotations

import dataclasses
import hashlib
import math
import subprocess
from collections.abc import Callable
from importlib import metadata, resources
from pathlib import Path
from typing import Any, Generic, TypeVar

import torch

from mrexplore.config import LearnedConfig, config_from_dict, config_to_dict
from mrexplore.global_planning.learned.ncm_network import NcmConfig, NcmNet
from mrexplore.global_planning.learned.network import MultiGraphNet
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
]

MAX_POLICY_BYTES = 64 << 20
"""Largest policy file read (the shipped one is 0.3 MB): a bigger file is refused before torch sees it."""
HIER_FORMAT = "mrexplore-policy-1"
NCM_FORMAT = "mrexplore-ncm-policy-1"
_KINDS = {HIER_FORMAT: "hier", NCM_FORMAT: "ncm"}
"""Format tag of a policy file -> the strategy it drives."""
VALUE_INPUTS = 4
"""Privileged scalars of the critic: remaining explorable area (m^2 / 100), coverage, steps / 1000, robots / 10."""


def default_policy_path() -> Path:
    """The pretrained ``hier`` policy shipped inside the package."""
    return Path(str(resources.files("mrexplore.global_planning.learned") / "pretrained" / "policy.pt"))


def default_ncm_policy_path() -> Path:
    """The pretrained ``ncm`` policy shipped inside the package."""
    return Path(str(resources.files("mrexplore.global_planning.learned") / "pretrained" / "ncm.pt"))


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


_Net = TypeVar("_Net", MultiGraphNet, NcmNet)


class LoadedPolicy(Generic[_Net]):
    """A network (the mGNN, or NCM's actor) with where it came from (path, sha256, what the file records)."""

    def __init__(self, net: _Net, path: Path, sha256: str, meta: dict[str, Any]) -> None:
        self.net: _Net = net
        self.path, self.sha256, self.meta = path, sha256, meta


LoadedNcmPolicy = LoadedPolicy[NcmNet]


def save_policy(path: Path, net: MultiGraphNet | NcmNet, meta: dict[str, Any] | None = None) -> None:
    """Write the weights (float32), the network's config, the code version and ``meta`` (plain data): a
    ``hier`` policy for a :class:`MultiGraphNet`, an ``ncm`` one (the actor alone) for an :class:`NcmNet`."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    state = {k: v.detach().float().contiguous() for k, v in net.state_dict().items()}
    head: dict[str, Any] = (
        {"format": NCM_FORMAT, "ncm_config": dataclasses.asdict(net.cfg)}
        if isinstance(net, NcmNet)
        else {"format": HIER_FORMAT, "learned_config": config_to_dict(net.cfg), "value_inputs": net.value_inputs}
    )
    blob = {
        **head,
        "state_dict": state,
        "weights_sha256": weights_digest(state),
        "code_version": code_version(),
        "meta": meta or {},
    }
    tmp = path.with_name(path.name + ".tmp")
    torch.save(blob, tmp)
    tmp.replace(path)  # atomic: a kill never leaves half a policy


def weights_digest(state: dict[str, torch.Tensor]) -> str:
    """sha256 over the weights (names, shapes and float32 bytes, in name order): a file whose weights were
    corrupted after saving no longer matches (torch's archive format checks no sums of its own)."""
    h = hashlib.sha256()
    for name in sorted(state):
        t = state[name].detach().float().contiguous().cpu()
        h.update(f"{name}{tuple(t.shape)}".encode())
        h.update(t.numpy().tobytes())
    return h.hexdigest()


def _read_policy(path: Path | None, default: Path, fmt: str) -> tuple[Path, dict[str, Any]]:
    """The checked blob of a policy file of format ``fmt``; one-line errors for every way it can be wrong."""
    path = Path(path) if path is not None else default
    if not path.is_file():
        raise MrExploreError(f"policy file {path} not found; pass a file written by 'mrexplore train' with --policy")
    if path.stat().st_size > MAX_POLICY_BYTES:
        raise MrExploreError(
            f"policy file {path} is {path.stat().st_size} bytes, over the {MAX_POLICY_BYTES}-byte limit of a policy"
        )
    try:
        blob = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # noqa: BLE001 - torch raises many kinds for a file that is not a checkpoint
        raise MrExploreError(
            f"policy file {path} is not a mrexplore policy ({type(exc).__name__}); retrain it"
        ) from None
    if not isinstance(blob, dict) or blob.get("format") not in _KINDS:
        raise MrExploreError(f"policy file {path} is not a mrexplore policy (no format tag); retrain it")
    if blob["format"] != fmt:
        have, want = _KINDS[blob["format"]], _KINDS[fmt]
        raise MrExploreError(
            f"policy file {path} is for the {have} strategy, not {want}; pass one written by "
            f"'mrexplore train --strategy {want}' (--policy {want}=FILE where a run has both)"
        )
    return path, blob


def _checked_state(blob: dict[str, Any]) -> dict[str, torch.Tensor]:
    state = blob["state_dict"]
    bad = [k for k, v in state.items() if not isinstance(v, torch.Tensor) or not torch.isfinite(v).all()]
    if bad:
        raise MrExploreError(f"weights {bad[0]} hold NaN or infinite values (or are no tensor)")
    if "weights_sha256" in blob and blob["weights_sha256"] != weights_digest(state):
        raise MrExploreError("weights do not match the digest saved with them: the file is corrupted")
    return dict(state)


_LOAD_ERRORS = (KeyError, TypeError, ValueError, AttributeError, RuntimeError, MrExploreError)


def _misfit(path: Path, exc: BaseException) -> MrExploreError:
    first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    return MrExploreError(f"policy file {path} does not fit this network ({first}); retrain it")


def _loaded(path: Path, blob: dict[str, Any], build: Callable[[], _Net], config_key: str) -> LoadedPolicy[_Net]:
    """The network ``build`` makes from ``blob``'s config, with the file's checked weights, in eval mode;
    any misfit is one line naming the file."""
    try:
        net = build()
        net.load_state_dict(_checked_state(blob))
    except _LOAD_ERRORS as exc:
        raise _misfit(path, exc) from None
    net.eval()
    meta = {k: blob[k] for k in ("code_version", "meta", config_key)}
    return LoadedPolicy(net, path, file_sha256(path), meta)


def load_policy(path: Path | None = None) -> LoadedPolicy[MultiGraphNet]:
    """Load a ``hier`` policy written by :func:`save_policy` (default: the shipped one); one-line errors."""
    path, blob = _read_policy(path, default_policy_path(), HIER_FORMAT)

    def build() -> MultiGraphNet:
        cfg = config_from_dict(LearnedConfig, blob["learned_config"])
        value_inputs = int(blob["value_inputs"])
        if value_inputs != VALUE_INPUTS:
            raise MrExploreError(f"the critic reads {value_inputs} scalars, this version {VALUE_INPUTS}")
        return MultiGraphNet(cfg, value_inputs)

    return _loaded(path, blob, build, "learned_config")


def load_ncm_policy(path: Path | None = None) -> LoadedNcmPolicy:
    """Load an ``ncm`` policy written by :func:`save_policy` (default: the shipped one); one-line errors."""
    path, blob = _read_policy(path, default_ncm_policy_path(), NCM_FORMAT)

    def build() -> NcmNet:
        raw = blob["ncm_config"]
        if not isinstance(raw, dict) or set(raw) != {f.name for f in dataclasses.fields(NcmConfig)}:
            raise ValueError("its network config has other fields")
        cfg = NcmConfig(**raw)
        if not (0 < cfg.hidden <= 512 and 0 < cfg.heads <= 16 and 0 < cfg.blocks <= 16 and cfg.hidden % cfg.heads == 0):
            raise ValueError(f"network sizes out of range: {cfg}")
        if not (0 < cfg.sinkhorn_iters <= 100 and math.isfinite(cfg.sharpen) and cfg.sharpen > 0):
            raise ValueError(f"Sinkhorn settings out of range: {cfg}")
        return NcmNet(cfg)

    return _loaded(path, blob, build, "ncm_config")
