"""Command line: one module per command, flags derived from the settings schema
(:mod:`~mrexplore.cli.settings_flags`); bad input is one line and exit 2."""

from mrexplore.cli.main import build_parser, main
from mrexplore.mission.record import strict_json

__all__ = ["main", "build_parser", "strict_json"]
