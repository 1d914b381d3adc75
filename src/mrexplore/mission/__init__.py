"""The team's application objects: the one replanning loop of a mission (:mod:`~mrexplore.mission.loop`), the
computing centre of a real team (:mod:`~mrexplore.mission.centre`), the decision-level environment over the
loop (:mod:`~mrexplore.mission.decision_env`) and the pictures of a mission (:mod:`~mrexplore.mission.render`).
The loop's names are importable from here."""

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
