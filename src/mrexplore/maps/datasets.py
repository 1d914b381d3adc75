"""The map datasets the loaders read: the examples shipped with the package, and where to get the larger ones
(their licences, their files and checksums), fetched by ``mrexplore maps get``. No map is downloaded at run
time otherwise.

Examples
--------
>>> sorted(DATASETS)
['dungeon', 'houseexpo', 'kth', 'ros']
>>> example_path("complex_img_43").name
'complex_img_43.png'
>>> len(DATASETS["dungeon"].files), len(DATASETS["houseexpo"].files)  # research data: never fetched
(30, 0)
"""

from __future__ import annotations

import csv
import hashlib
import urllib.error
import urllib.request
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from mrexplore.types import MrExploreError

__all__ = ["Dataset", "DataFile", "DATASETS", "EXAMPLES_DIR", "example_path", "example_names", "get_dataset"]

EXAMPLES_DIR = Path(__file__).with_name("examples")
"""The maps shipped with the package (examples/README.md gives their sources and licences)."""
_MAP_SUFFIXES = (".yaml", ".png", ".json")


@dataclass(frozen=True)
class DataFile:
    """One file of a dataset: its name here, its path in the source repository, its SHA-256."""

    name: str
    source_path: str
    sha256: str


@dataclass(frozen=True)
class Dataset:
    """A dataset the loaders read."""

    title: str
    licence: str
    where: str
    """Where to get it, in words (a repository and its folder)."""
    base_url: str = ""
    """The source repository's raw files at a fixed commit; a file's URL is this plus its ``source_path``."""
    files: tuple[DataFile, ...] = field(default=())
    """What ``mrexplore maps get`` fetches (empty: it fetches nothing, and says where to get it)."""
    shipped: tuple[str, ...] = ()
    """Its files that ship with the package as examples (none where its licence does not allow it)."""


def _dungeon_files() -> tuple[DataFile, ...]:
    with open(Path(__file__).with_name("datasets_dungeon.csv"), newline="") as f:
        return tuple(DataFile(r["file"], r["source_path"], r["sha256"]) for r in csv.DictReader(f))


DATASETS = {
    "dungeon": Dataset(
        "DungeonMaps (ARiADNE / Chen et al.): 30 procedural dungeon maps, 10 easy, 10 medium, 10 complex",
        "MIT (ARiADNE) and BSD-3-Clause (Chen et al.)",
        "github.com/marmotlab/ARiADNE, DungeonMaps/{easy,medium,complex}/",
        "https://raw.githubusercontent.com/marmotlab/ARiADNE/8d726ad05e6b0c38672f1679baf7fa2b083a0eb0/",
        _dungeon_files(),
        ("complex_img_43", "complex_img_81", "medium_img_13", "easy_img_15"),
    ),
    "ros": Dataset(
        "two real SLAM maps in ROS map_server format: the Willow Garage office (0.1 m), a basement (0.05 m)",
        "BSD (turtlebot_navigation), Apache-2.0 (range_libc)",
        "github.com/turtlebot/turtlebot_apps turtlebot_navigation/maps/; github.com/castacks/MapEx range_libc/maps/",
        "https://raw.githubusercontent.com/",
        (
            DataFile(
                "willow-2010-02-18-0.10.pgm",
                "turtlebot/turtlebot_apps/4bbafc7bfdfc5888ba03b52611bdb56d86b22967/turtlebot_navigation/maps/"
                "willow-2010-02-18-0.10.pgm",
                "d7644ea5eabbbc77dcb6f136774f9b159a6514151f9c411bbd6c383f592bd6e0",
            ),
            DataFile(
                "willow-2010-02-18-0.10.yaml",
                "turtlebot/turtlebot_apps/4bbafc7bfdfc5888ba03b52611bdb56d86b22967/turtlebot_navigation/maps/"
                "willow-2010-02-18-0.10.yaml",
                "e10d1ba93e8f204a581641a5da85d6803c89c4216e619637a2fcfe0317d290af",
            ),
            DataFile(
                "basement_hallways_5cm.png",
                "castacks/MapEx/b607ed3dcbf03ba65811cced35a25968fbbc454a/range_libc/maps/basement_hallways_5cm.png",
                "0e96b2c8b928467b597e977fc738a05792d459699739ba402e1b2d96a8e9a5e9",
            ),
        ),
        ("willow-2010-02-18-0.10", "basement_hallways_5cm"),
    ),
    "houseexpo": Dataset(
        "HouseExpo: 35,126 floor plans as JSON (metres), built on SUNCG",
        "research use only (the layouts come from SUNCG); the repository's code is MIT",
        "github.com/TeaganLi/HouseExpo (its HouseExpo/json.tar.gz); read with --map FILE.json",
    ),
    "kth": Dataset(
        "KTH campus floor plans (Aydemir et al.), as MapEx prepared them",
        "research data (no terms stated for the KTH floor plans); MapEx's code is Clear BSD",
        "github.com/castacks/MapEx, kth_test_maps/ (occ_map.npy: save it as a PNG with a map_server YAML)",
    ),
}
"""Every dataset by name."""


def example_names() -> list[str]:
    """The shipped examples' names (``--map example:NAME``)."""
    return sorted({p.stem for p in EXAMPLES_DIR.iterdir() if p.suffix in (*_MAP_SUFFIXES, ".pgm")})


def example_path(name: str) -> Path:
    """The file of the shipped example ``name`` (its YAML where it has one); one line listing them otherwise."""
    for suffix in _MAP_SUFFIXES:
        path = EXAMPLES_DIR / f"{name}{suffix}"
        if path.is_file():
            return path
    raise MrExploreError(f"no example map {name!r}; the examples: {', '.join(example_names())}")


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _fetch(source: str, f: DataFile) -> bytes:
    """The bytes of ``f`` from ``source``: a folder holding it (by its name, or its source path) or a URL base."""
    folder = Path(source)
    if "://" not in source:
        for candidate in (folder / f.name, folder / f.source_path):
            if candidate.is_file():
                return candidate.read_bytes()
        raise MrExploreError(f"{f.name} is not in {folder}; give the folder that holds the dataset's files")
    url = source + f.source_path
    try:
        with urllib.request.urlopen(url, timeout=60) as response:  # noqa: S310 - a URL base the user named
            data: bytes = response.read()
            return data
    except (urllib.error.URLError, OSError) as exc:
        raise MrExploreError(f"{url} could not be read ({exc}); check the network, or use --from FOLDER") from None


def get_dataset(name: str, dest: Path, source: str | None = None, say: Callable[[str], None] = print) -> list[Path]:
    """Fetch dataset ``name`` into ``dest`` from its repository (or ``source``: a folder or a URL base), each
    file checked against its SHA-256 and written whole or not at all; a file already there with the right
    checksum is kept. Returns the files."""
    if name not in DATASETS:
        raise MrExploreError(f"no dataset {name!r}; the datasets: {', '.join(sorted(DATASETS))}")
    ds = DATASETS[name]
    if not ds.files:
        raise MrExploreError(f"{name} is not fetched by mrexplore ({ds.licence}); get it from {ds.where}")
    dest.mkdir(parents=True, exist_ok=True)
    got = []
    for k, f in enumerate(ds.files, 1):
        target = dest / f.name
        if target.is_file() and _sha256(target.read_bytes()) == f.sha256:
            say(f"[{k}/{len(ds.files)}] {f.name}: already there")
        else:
            data = _fetch(source or ds.base_url, f)
            if _sha256(data) != f.sha256:
                raise MrExploreError(
                    f"{f.name} has SHA-256 {_sha256(data)[:12]}..., not {f.sha256[:12]}...: the source changed or "
                    "the transfer broke; nothing was written for it (run it again, or use --from FOLDER)"
                )
            tmp = target.with_suffix(target.suffix + ".part")
            tmp.write_bytes(data)
            tmp.replace(target)
            say(f"[{k}/{len(ds.files)}] {f.name}: {len(data):,} bytes, checksum right")
        got.append(target)
    for stem in ds.shipped:  # what the package adds beside the source's files (the basement's YAML)
        mine = EXAMPLES_DIR / f"{stem}.yaml"
        if mine.is_file() and not (dest / mine.name).exists():
            (dest / mine.name).write_bytes(mine.read_bytes())
            got.append(dest / mine.name)
    return got
