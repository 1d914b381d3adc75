"""Where the example maps are (the dev maps, the training maps): one setting that the CLI, the tests and the
benchmarks read, the ``MREXPLORE_MAPS`` environment variable, or ``--maps-dir`` on the command line."""

from __future__ import annotations

from pathlib import Path

from mrexplore.config.run import runtime_value

__all__ = ["MAPS_ENV", "DEFAULT_MAPS_DIR", "DEFAULT_MAP", "maps_dir"]

DEFAULT_MAP = "generated:0"
"""The map a mission explores when none is given: a procedural floor plan."""

MAPS_ENV = "MREXPLORE_MAPS"
"""The environment variable of the ``runtime.maps_dir`` setting, naming the example maps' folder."""
DEFAULT_MAPS_DIR = Path("..") / "shared" / "maps"
"""Where the example maps are when nothing says otherwise: beside a clone of the repository."""


def maps_dir() -> Path:
    """The example maps' folder: the ``runtime.maps_dir`` setting (``$MREXPLORE_MAPS``), else
    ``../shared/maps`` (from the working directory).

    Examples
    --------
    >>> import os
    >>> os.environ[MAPS_ENV] = "/data/maps"
    >>> str(maps_dir())
    '/data/maps'
    >>> del os.environ[MAPS_ENV]
    >>> maps_dir() == DEFAULT_MAPS_DIR
    True
    """
    given: str | None = runtime_value("maps_dir")
    return Path(given) if given else DEFAULT_MAPS_DIR
