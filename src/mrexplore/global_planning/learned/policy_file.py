"""Policy files without torch: NumPy archives of float32 weights with a JSON header (format, network config,
weights digest, code version, meta), read with ``allow_pickle=False`` (a policy file runs no code).

A policy in torch's archive format, as older versions wrote them, is read by training's loaders (which have
torch); deciding refuses it in one line saying so.
"""

from __future__ import annotations

import dataclasses
import json
import math
import zipfile
from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import Any, Generic, TypeVar

import numpy as np
from numpy.typing import NDArray

from mrexplore.config import LearnedConfig, config_from_dict
from mrexplore.global_planning.learned.ncm_inputs import NcmConfig
from mrexplore.global_planning.learned.numpy_nets import GraphNetNp, NcmNetNp
from mrexplore.runtime.weights_archive import HEADER_MEMBER as _HEADER
from mrexplore.runtime.weights_archive import WEIGHT_PREFIX as _WEIGHT
from mrexplore.runtime.weights_archive import code_version, file_sha256, weights_digest
from mrexplore.runtime.weights_archive import write_weights_archive as write_policy_file
from mrexplore.types import MrExploreError

__all__ = [
    "LoadedPolicy",
    "load_policy_np",
    "load_ncm_policy_np",
    "hier_config",
    "ncm_config",
    "HIER_FORMAT",
    "NCM_FORMAT",
    "MAX_POLICY_BYTES",
    "PolicyFile",
    "code_version",
    "default_ncm_policy_path",
    "default_policy_path",
    "file_sha256",
    "read_policy_file",
    "weights_digest",
    "write_policy_file",
]

MAX_POLICY_BYTES = 64 << 20
"""Largest policy file read (the shipped ones are under 1 MB): a bigger file is refused before it is opened."""
HIER_FORMAT = "mrexplore-policy-1"
NCM_FORMAT = "mrexplore-ncm-policy-1"
KINDS = {HIER_FORMAT: "hier", NCM_FORMAT: "ncm"}
"""Format tag of a policy file -> the strategy it drives."""

VALUE_INPUTS = 4
"""Privileged scalars of the critic: remaining explorable area (m^2 / 100), coverage, steps / 1000, robots / 10."""

State = dict[str, NDArray[np.float32]]
_Net = TypeVar("_Net")


def default_policy_path() -> Path:
    """The pretrained ``hier`` policy shipped inside the package."""
    return Path(str(resources.files("mrexplore.global_planning.learned") / "pretrained" / "policy.npz"))


def default_ncm_policy_path() -> Path:
    """The pretrained ``ncm`` policy shipped inside the package."""
    return Path(str(resources.files("mrexplore.global_planning.learned") / "pretrained" / "ncm.npz"))


class PolicyFile:
    """A policy file's checked content: its header (format, network config, code version, meta) and its
    float32 weights by name, with the path and the file's sha256."""

    def __init__(self, path: Path, header: dict[str, Any], state: State, sha256: str) -> None:
        self.path, self.header, self.state, self.sha256 = path, header, state, sha256

    @property
    def meta(self) -> dict[str, Any]:
        """What loading reports: the code version, the trainer's meta and the network config."""
        config_key = "ncm_config" if self.header["format"] == NCM_FORMAT else "learned_config"
        return {k: self.header.get(k) for k in ("code_version", "meta", config_key)}


TorchReader = Callable[[Path], "tuple[dict[str, Any], State]"]
"""Reads a policy in torch's archive format (training's loaders hand one in)."""


def read_policy_file(path: Path | None, fmt: str, read_torch: TorchReader | None = None) -> PolicyFile:
    """The checked content of a policy file of format ``fmt`` (default: the shipped one of that format);
    one-line errors for every way it can be wrong."""
    default = default_ncm_policy_path() if fmt == NCM_FORMAT else default_policy_path()
    path = Path(path) if path is not None else default
    if not path.is_file():
        raise MrExploreError(f"policy file {path} not found; pass a file written by 'mrexplore train' with --policy")
    if path.stat().st_size > MAX_POLICY_BYTES:
        raise MrExploreError(
            f"policy file {path} is {path.stat().st_size} bytes, over the {MAX_POLICY_BYTES}-byte limit of a policy"
        )
    header, state = _read_any(path, read_torch)
    if header.get("format") not in KINDS:
        raise _not_policy(path, "no format tag")
    if header["format"] != fmt:
        have, want = KINDS[header["format"]], KINDS[fmt]
        raise MrExploreError(
            f"policy file {path} is for the {have} strategy, not {want}; pass one written by "
            f"'mrexplore train --strategy {want}' (--policy {want}=FILE where a run has both)"
        )
    bad = [k for k, v in state.items() if not np.isfinite(v).all()]
    if bad:
        raise MrExploreError(f"policy file {path} has weights {bad[0]} holding NaN or infinite values; retrain it")
    if "weights_sha256" in header and header["weights_sha256"] != weights_digest(state):
        raise MrExploreError(
            f"policy file {path} is corrupted: its weights do not match the digest saved with them; retrain it"
        )
    return PolicyFile(path, header, state, file_sha256(path))


def _not_policy(path: Path, why: str) -> MrExploreError:
    return MrExploreError(f"policy file {path} is not a mrexplore policy ({why}); retrain it")


def _read_any(path: Path, read_torch: TorchReader | None) -> tuple[dict[str, Any], State]:
    """Header and weights of a NumPy policy archive, or of a torch one (older versions) where a reader of them
    is given."""
    try:
        with zipfile.ZipFile(path) as z:
            names = z.namelist()
            unpacked = sum(info.file_size for info in z.infolist())
    except (zipfile.BadZipFile, OSError):
        raise _not_policy(path, "not an archive") from None
    if unpacked > MAX_POLICY_BYTES:  # a compressed member could unpack far beyond the file's own size
        raise _not_policy(path, f"it unpacks to {unpacked} bytes, over the {MAX_POLICY_BYTES}-byte limit")
    if _HEADER + ".npy" in names:
        return _read_npz(path)
    if any(n.endswith("data.pkl") for n in names):
        if read_torch is None:
            raise MrExploreError(
                f"policy file {path} is in torch's format (an older mrexplore wrote it); load it once with "
                "mrexplore.training.checkpoint.load_policy and write it with save_policy (needs torch), or retrain it"
            )
        return read_torch(path)
    raise _not_policy(path, "no header")


def _read_npz(path: Path) -> tuple[dict[str, Any], State]:
    try:
        with np.load(path, allow_pickle=False) as z:
            header = json.loads(bytes(z[_HEADER]).decode())
            state = {k[len(_WEIGHT) :]: np.asarray(z[k], np.float32) for k in z.files if k.startswith(_WEIGHT)}
    except (ValueError, OSError, UnicodeDecodeError, zipfile.BadZipFile, EOFError) as exc:
        raise MrExploreError(
            f"policy file {path} is not a mrexplore policy ({type(exc).__name__}); retrain it"
        ) from None
    if not isinstance(header, dict):
        raise _not_policy(path, "its header is no mapping")
    return header, state


class LoadedPolicy(Generic[_Net]):
    """A network (NumPy or torch; the mGNN or NCM's actor) with where it came from (path, sha256, what the
    file records)."""

    def __init__(self, net: _Net, path: Path, sha256: str, meta: dict[str, Any]) -> None:
        self.net: _Net = net
        self.path, self.sha256, self.meta = path, sha256, meta


def hier_config(pf: PolicyFile) -> tuple[LearnedConfig, int]:
    """A ``hier`` policy's network config and its critic's input count (checked)."""
    cfg = config_from_dict(LearnedConfig, pf.header["learned_config"])
    value_inputs = int(pf.header["value_inputs"])
    if value_inputs != VALUE_INPUTS:
        raise MrExploreError(f"the critic reads {value_inputs} scalars, this version {VALUE_INPUTS}")
    return cfg, value_inputs


def ncm_config(pf: PolicyFile) -> NcmConfig:
    """An ``ncm`` policy's network config (checked)."""
    raw = pf.header["ncm_config"]
    if not isinstance(raw, dict) or set(raw) != {f.name for f in dataclasses.fields(NcmConfig)}:
        raise ValueError("its network config has other fields")
    cfg = NcmConfig(**raw)
    if not (0 < cfg.hidden <= 512 and 0 < cfg.heads <= 16 and 0 < cfg.blocks <= 16 and cfg.hidden % cfg.heads == 0):
        raise ValueError(f"network sizes out of range: {cfg}")
    if not (0 < cfg.sinkhorn_iters <= 100 and math.isfinite(cfg.sharpen) and cfg.sharpen > 0):
        raise ValueError(f"Sinkhorn settings out of range: {cfg}")
    return cfg


LOAD_ERRORS = (KeyError, TypeError, ValueError, AttributeError, RuntimeError, MrExploreError)


def built(pf: PolicyFile, build: Callable[[], _Net]) -> LoadedPolicy[_Net]:
    """The network ``build`` makes from ``pf``; any misfit is one line naming the file."""
    try:
        net = build()
    except LOAD_ERRORS as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise MrExploreError(f"policy file {pf.path} does not fit this network ({first}); retrain it") from None
    return LoadedPolicy(net, pf.path, pf.sha256, pf.meta)


def load_policy_np(path: Path | None = None) -> LoadedPolicy[GraphNetNp]:
    """A ``hier`` policy file (default: the shipped one) as the NumPy network; one-line errors."""
    pf = read_policy_file(path, HIER_FORMAT)
    return built(pf, lambda: GraphNetNp(hier_config(pf)[0], pf.state))


def load_ncm_policy_np(path: Path | None = None) -> LoadedPolicy[NcmNetNp]:
    """An ``ncm`` policy file (default: the shipped one) as the NumPy network; one-line errors."""
    pf = read_policy_file(path, NCM_FORMAT)
    return built(pf, lambda: NcmNetNp(ncm_config(pf), pf.state))
