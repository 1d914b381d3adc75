"""The team's application objects: the one replanning loop of a mission (:mod:`~mrexplore.mission.loop`), the
computing centre of a real team (:mod:`~mrexplore.mission.centre`), the decision-level environment over the
loop (:mod:`~mrexplore.mission.decision_env`), the pictures of a mission (:mod:`~mrexplore.mission.render`) and
its record (:mod:`~mrexplore.mission.record`). The loop's names are importable from here; the loop itself is
imported at the first use of one (the record and the command line need none of it)."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from mrexplore.mission.loop import (
        Centre,
        FaultSchedule,
        MeasuresRecorder,
        Mission,
        MissionResult,
        MissionSnapshot,
        MissionSpec,
        Observer,
        run_mission,
    )

__all__ = [
    "Mission",
    "MissionSpec",
    "MissionResult",
    "MissionSnapshot",
    "FaultSchedule",
    "MeasuresRecorder",
    "run_mission",
    "Observer",
    "Centre",
]


def __getattr__(name: str) -> Any:
    if name not in __all__:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.loop"), name)
