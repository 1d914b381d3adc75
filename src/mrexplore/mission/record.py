"""What a mission leaves for people and files: its record (what ran, its measures, the starts and every
setting; what ``mrexplore explore --json`` and ``ros2 launch --json`` print), its text summary, and strict
JSON of it."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from mrexplore.config import RunConfig, TrainConfig, config_to_dict
from mrexplore.runtime.kernel_cache import compiled_this_run

__all__ = ["mission_record", "strict_json", "summary", "launch_summary"]


def mission_record(
    run: RunConfig, strategy: Any, truth: Any, seed: int, measures: dict[str, Any], starts_rc: Any
) -> dict[str, Any]:
    """explore's record of one mission: what ran, its measures, the starts and every setting."""
    record: dict[str, Any] = {
        "strategy": strategy.name,
        "map": truth.name,
        "robots": run.sim.robots,
        "seed": seed,
        **measures,
        "starts_xy": [list(truth.frame.rc_to_xy((int(r), int(c)))) for r, c in starts_rc],
        "policy": strategy.policy,
        "predictor": strategy.predictor,
        "config": {
            **config_to_dict(replace(run, train=TrainConfig())),
            "strategy": {
                "preprocess": config_to_dict(strategy.preprocess),
                "commitment": strategy.commitment,
                "local": config_to_dict(strategy.local.cfg) if strategy.local is not None else None,
            },
        },
    }
    del record["config"]["train"], record["config"]["runtime"]  # how this process ran, not the mission
    return record


def strict_json(value: Any) -> Any:
    """``value`` with every NaN or infinite float as None and tuples as lists: strict JSON, which
    ``json.dumps(..., allow_nan=False)`` then always accepts."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {str(k): strict_json(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [strict_json(v) for v in value]
    if hasattr(value, "item") and hasattr(value, "dtype") and getattr(value, "ndim", None) == 0:  # NumPy scalar
        return strict_json(value.item())
    return value


def _kb(n: int | None) -> str:
    return "not counted" if n is None else f"{n / 1e3:.1f} kB"


def launch_summary(rec: dict[str, Any]) -> str:
    """What ``ros2 launch`` prints: explore's summary in lockstep, the real-time run's few measures otherwise,
    and what crossed the middleware."""
    wire = rec["wire"]
    head = (
        summary(rec)
        if rec["lockstep"]
        else f"explored {rec['map']} with {rec['robots']} robots ({rec['strategy']}, seed {rec['seed']}) in real time\n"
        f"  coverage {100 * rec['coverage']:.2f}% in {rec['steps']} steps; ended: {rec['done_reason']}"
    )
    return (
        f"{head}\n  through ROS 2: {wire['messages']} frontier messages, {_kb(wire['payload_bytes'])} "
        f"({_kb(wire['serialized_bytes'])} serialized); {rec['centre']['decisions']} decisions, "
        f"{rec['decision_ms_median']:.1f} ms median from the last message in to every goal out; "
        f"{rec['centre']['aborts']} goals aborted; logs in {rec['logs']}"
    )


def summary(rec: dict[str, Any]) -> str:
    def at(key: str) -> str:
        return "never" if rec[key] is None else str(rec[key])

    return "\n".join(
        [
            f"explored {rec['map']} with {rec['robots']} robots ({rec['strategy']}, seed {rec['seed']})",
            f"  coverage {100 * rec['coverage']:.2f}% of the free space in {rec['steps']} steps "
            f"(90% at step {at('steps_to_90')}, 95% at {at('steps_to_95')}, 99% at {at('steps_to_99')})",
            f"  driven: the longest robot {rec['path_len_max_m']:.1f} m, the team {rec['path_len_sum_m']:.1f} m; "
            f"overlap {rec['overlap']:.2f} (0: no cell seen twice)",
            f"  the centre decided {rec['decisions']} times: {rec['plan_ms_mean']:.1f} ms mean, "
            f"{rec['plan_ms_p95']:.1f} ms p95; wall {rec['wall_s']:.1f} s; peak memory {rec['peak_mb']:.0f} MB; "
            f"ended: {rec['done_reason']}",
            f"  each robot's own work a round, its map into its message: {rec['onboard_ms_median']:.1f} ms median, "
            f"{rec['onboard_ms_p95']:.1f} ms p95",
            f"  sent over {rec['rounds']} rounds: {_kb(rec['bytes_sparse_delta'])} of sparse frontier deltas "
            f"(whole sparse maps: {_kb(rec['bytes_sparse'])}; whole grids: {_kb(rec['bytes_grid'])},",
            f"    zlib-compressed {_kb(rec['bytes_grid_zlib'])}); the centre's map against the robots': "
            f"IoU at least {rec['reconstruction_iou_min']:.4f} (1: exact)",
            *(
                [
                    f"  faults: {rec['robots_failed']} robots failed, {rec['messages_lost']} of "
                    f"{rec['messages_sent']} messages lost, {rec['messages_resent']} whole maps resent, "
                    f"{rec['acks_lost']} acknowledgements lost, {rec['centre_restarts']} centre restarts"
                ]
                if any(rec[k] for k in ("robots_failed", "messages_lost", "messages_resent", "centre_restarts"))
                else []
            ),
            *(
                ["  this first run's times include compiling the kernels; later runs are faster"]
                if compiled_this_run()
                else []
            ),
            "  (each figure in docs/usage.md, 'Reading the summary')",
        ]
    )
