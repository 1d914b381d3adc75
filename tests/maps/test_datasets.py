"""The maps that ship with the package and ``mrexplore maps get``: each example loads by name; a dataset is
fetched from a local copy or a file:// URL, every file checked by its SHA-256 (a changed file is refused and
nothing written for it, a file already right is kept); research data is never fetched."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import pytest

from mrexplore.cli import main
from mrexplore.config import MapConfig
from mrexplore.maps import datasets
from mrexplore.maps.datasets import DATASETS, EXAMPLES_DIR, DataFile, Dataset, example_names, get_dataset
from mrexplore.maps.loaders import load_map
from mrexplore.types import MrExploreError


@pytest.mark.parametrize("name", example_names())
def test_every_shipped_example_loads_by_name(name: str) -> None:
    truth = load_map(f"example:{name}", MapConfig(resolution_m=0.1))
    assert truth.occupied.any() and (~truth.occupied).sum() > 1000


def test_an_unknown_example_is_one_line_listing_them() -> None:
    with pytest.raises(MrExploreError) as err:
        load_map("example:nowhere")
    assert str(err.value) == f"no example map 'nowhere'; the examples: {', '.join(example_names())}"


def test_the_shipped_examples_are_the_datasets_files_byte_for_byte() -> None:
    for ds in DATASETS.values():
        for f in ds.files:
            shipped = EXAMPLES_DIR / f.name
            if shipped.is_file():
                assert hashlib.sha256(shipped.read_bytes()).hexdigest() == f.sha256, f.name


@pytest.fixture
def tiny(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Path:
    """A dataset of two shipped files, its source a folder laid out as the repository is."""
    source = tmp_path / "repo"
    files = []
    for name in ("easy_img_15.png", "medium_img_13.png"):
        data = (EXAMPLES_DIR / name).read_bytes()
        (source / "maps").mkdir(parents=True, exist_ok=True)
        (source / "maps" / name).write_bytes(data)
        files.append(DataFile(name, f"maps/{name}", hashlib.sha256(data).hexdigest()))
    monkeypatch.setitem(DATASETS, "tiny", Dataset("two maps", "MIT", "here", source.as_uri() + "/", tuple(files)))
    return source


def test_a_dataset_is_fetched_checked_and_kept(tiny: Path, tmp_path: Path) -> None:
    said: list[str] = []
    got = get_dataset("tiny", tmp_path / "out", say=said.append)  # from its URL base (file://)
    assert [p.name for p in got] == ["easy_img_15.png", "medium_img_13.png"]
    size = (EXAMPLES_DIR / "easy_img_15.png").stat().st_size
    assert said == [f"[1/2] easy_img_15.png: {size:,} bytes, checksum right", said[1]]
    said.clear()
    get_dataset("tiny", tmp_path / "out", str(tiny / "maps"), say=said.append)  # a local copy, by file name
    assert said == ["[1/2] easy_img_15.png: already there", "[2/2] medium_img_13.png: already there"]


def test_a_changed_file_is_refused_and_nothing_is_written_for_it(tiny: Path, tmp_path: Path) -> None:
    (tiny / "maps" / "medium_img_13.png").write_bytes(b"not the map")
    with pytest.raises(MrExploreError) as err:
        get_dataset("tiny", tmp_path / "out", say=lambda line: None)
    assert str(err.value).startswith("medium_img_13.png has SHA-256 ")
    assert str(err.value).endswith("nothing was written for it (run it again, or use --from FOLDER)")
    assert sorted(os.listdir(tmp_path / "out")) == ["easy_img_15.png"]


def test_research_data_is_never_fetched_and_the_listing_says_where_to_get_it(capsys: pytest.CaptureFixture) -> None:
    assert main(["maps", "get", "houseexpo", "--dest", "unused"]) == 2
    assert "houseexpo is not fetched by mrexplore (research use only" in capsys.readouterr().err
    assert main(["maps"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("shipped with mrexplore (--map example:NAME): basement_hallways_5cm, complex_img_43")
    assert "  get it:  mrexplore maps get dungeon --dest DIR" in out
    assert not datasets.DATASETS["kth"].files and not datasets.DATASETS["kth"].shipped  # research data


def test_the_dev_dungeon_maps_come_from_a_local_copy(tmp_path: Path) -> None:
    local = Path(os.environ.get("MREXPLORE_MAPS", "../shared/maps")) / "dungeon"
    if not local.is_dir():
        pytest.skip(f"no local copy of the DungeonMaps at {local} (set MREXPLORE_MAPS)")
    assert main(["maps", "get", "dungeon", "--dest", str(tmp_path), "--from", str(local)]) == 0
    assert len(list(tmp_path.glob("*.png"))) == 30
