"""Fuzzing the map loaders and the policy loader: random bytes under every map suffix (hypothesis) and seeded
mutations of the real files in ../shared/maps end in a map or in one MrExploreError line, never anything
else. ``perf/fuzz_inputs.py`` runs the same mutations far longer and writes what it found."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import SHARED_MAPS
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mrexplore.config import MapConfig
from mrexplore.maps.ground_truth import GroundTruthMap
from mrexplore.maps.loaders import load_map
from mrexplore.training.checkpoint import default_policy_path, load_policy
from mrexplore.types import MrExploreError

FUZZ_CFG = MapConfig(resolution_m=0.1, max_image_pixels=4_000_000, max_cells=1_000_000)
"""Small limits: a mutated header may claim any size; what the limits allow stays fast."""
REAL_FILES = (
    ("houseexpo/json/0004d52d1aeeb8ae6de39d6bd993e992.json",),
    ("dungeon/easy_img_15.png",),
    ("ros/basement_hallways_5cm.yaml", "ros/basement_hallways_5cm.png"),
)
"""Each entry: the file to load first, then the files it reads (all mutated the same way)."""


def mutate(data: bytes, rng: np.random.Generator) -> bytes:
    """One seeded mutation: flipped bytes, a cut, a duplicated or deleted span, or random bytes spliced in."""
    buf = bytearray(data)
    kind = int(rng.integers(5))
    if kind == 0 and buf:
        for i in rng.integers(0, len(buf), size=int(rng.integers(1, 9))):
            buf[int(i)] ^= int(rng.integers(1, 256))
    elif kind == 1:
        buf = buf[: int(rng.integers(0, len(buf) + 1))]
    elif kind == 2 and buf:
        a = int(rng.integers(len(buf)))
        b = min(len(buf), a + int(rng.integers(1, 64)))
        buf[a:a] = buf[a:b] * int(rng.integers(1, 4))
    elif kind == 3 and buf:
        a = int(rng.integers(len(buf)))
        del buf[a : a + int(rng.integers(1, 64))]
    else:
        a = int(rng.integers(len(buf) + 1))
        buf[a:a] = rng.integers(0, 256, size=int(rng.integers(1, 32)), dtype=np.uint8).tobytes()
    return bytes(buf)


def load_outcome(path: Path, cfg: MapConfig = FUZZ_CFG) -> str:
    """``"map"`` or ``"error: <first words>"``; anything but a map or a one-line MrExploreError propagates."""
    try:
        m = load_map(path, cfg)
    except MrExploreError as exc:
        assert "\n" not in str(exc)
        return "error: " + " ".join(str(exc).split()[:3])
    assert isinstance(m, GroundTruthMap) and m.occupied.dtype == bool and (~m.occupied).any()
    return "map"


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.binary(max_size=2000), suffix=st.sampled_from([".png", ".pgm", ".json", ".yaml", ".jpg"]))
def test_random_bytes_under_every_suffix(tmp_path, data: bytes, suffix: str) -> None:
    p = tmp_path / f"fuzz{suffix}"
    p.write_bytes(data)
    assert load_outcome(p).startswith(("map", "error: "))


def mutated_copy(root: Path, files: tuple[str, ...], out: Path, rng: np.random.Generator) -> Path:
    """Copy a real map (and the files it reads) into ``out`` with one of them mutated; returns the entry."""
    victim = int(rng.integers(len(files)))
    for i, name in enumerate(files):
        data = (root / name).read_bytes()
        (out / Path(name).name).write_bytes(mutate(data, rng) if i == victim else data)
    return out / Path(files[0]).name


@pytest.mark.parametrize("entry", range(len(REAL_FILES)))
def test_mutations_of_real_map_files(tmp_path, entry: int) -> None:
    if not SHARED_MAPS.is_dir():
        pytest.skip(f"shared maps not found at {SHARED_MAPS}; real-file fuzzing needs ../shared/maps")
    rng = np.random.default_rng(entry)
    outcomes = [load_outcome(mutated_copy(SHARED_MAPS, REAL_FILES[entry], tmp_path, rng)) for _ in range(25)]
    assert any(o.startswith("error: ") for o in outcomes)  # the mutations do reach the error paths


def test_mutations_of_the_shipped_policy(tmp_path) -> None:
    data = default_policy_path().read_bytes()
    rng = np.random.default_rng(0)
    refused = 0
    for i in range(12):
        p = tmp_path / f"p{i}.npz"
        p.write_bytes(mutate(data, rng))
        try:
            load_policy(p)
        except MrExploreError as exc:
            assert "\n" not in str(exc)
            refused += 1
    assert refused > 0
