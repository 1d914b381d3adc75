"""``mrexplore maps``: the map datasets the loaders read, with their licences and where to get each; ``maps get``
fetches one from its public repository, each file checked by its checksum."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

__all__ = ["add_maps", "run_maps"]

_HELP = """The maps mrexplore reads: the examples shipped with it (--map example:NAME) and the datasets of the
benchmarks, with their licences and where to get each.

examples:
  mrexplore maps
  mrexplore maps get dungeon --dest maps/dungeon
  mrexplore --maps-dir maps bench --maps maps/dungeon --robots 3"""


def add_maps(sub: Any) -> None:
    mp = sub.add_parser(
        "maps",
        help="list the map datasets (licences, where to get them); 'maps get NAME' fetches one",
        description=_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    kinds = mp.add_subparsers(dest="maps")
    get = kinds.add_parser("get", help="fetch a dataset from its public repository, checked by checksum")
    get.add_argument("name", help="the dataset: dungeon or ros (the others are research data: see 'mrexplore maps')")
    get.add_argument("--dest", required=True, metavar="DIR", help="the folder to write its files in")
    get.add_argument(
        "--from",
        dest="source",
        default=None,
        metavar="FOLDER|URL",
        help="read the files from a local copy (a folder) or another URL base instead of the repository",
    )


def run_maps(args: argparse.Namespace) -> str:
    from mrexplore.cli.common import check_output
    from mrexplore.maps.datasets import DATASETS, example_names, get_dataset

    if args.maps == "get":
        check_output(args.dest, "--dest", folder=True)
        files = get_dataset(args.name, Path(args.dest), args.source, say=lambda line: print(line, file=sys.stderr))
        return f"{len(files)} files of {args.name} in {args.dest}"
    lines = ["shipped with mrexplore (--map example:NAME): " + ", ".join(example_names()), ""]
    for name, ds in DATASETS.items():
        how = f"mrexplore maps get {name} --dest DIR" if ds.files else "not fetched by mrexplore"
        lines += [
            f"{name}: {ds.title}",
            f"  licence: {ds.licence}",
            f"  where:   {ds.where}",
            f"  get it:  {how}",
        ]
    return "\n".join(lines)
