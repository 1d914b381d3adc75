"""The trainer end to end on tiny budgets: stages, logs, checkpoints, resume after a stop, refusals."""

from __future__ import annotations

import csv
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path

import pytest
import torch

from mrexplore.config import EpisodesConfig, NcmTrainConfig, TrainConfig
from mrexplore.training.checkpoint import load_policy
from mrexplore.training.trainer import LOG_COLUMNS, split_maps, train
from mrexplore.types import MrExploreError

TINY_EPISODES = EpisodesConfig(resolution_m=0.2, robots_min=2, robots_max=2, max_steps=80)
TINY = TrainConfig(
    episodes=TINY_EPISODES,
    val_maps=1,
    search_generations=0,
    dagger_rounds=1,
    episodes_per_round=1,
    horizon_steps=20,
    noisy_candidates=1,
    imitation_epochs=1,
    ppo_iterations=1,
    ppo_episodes=1,
    ppo_epochs=1,
)


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_stop_and_resume_runs_every_stage_once(tmp_path: Path) -> None:
    out = tmp_path / "run"
    first = train(TINY, out, None, episodes=1, workers=1, seed=3)  # baseline and dagger0, then the budget ends
    assert [r["stage"] for r in first.stages] == ["baseline", "dagger0"]
    with pytest.raises(MrExploreError, match=r"already holds a training run; pass --resume to continue it"):
        train(TINY, out, None, workers=1)
    with pytest.raises(MrExploreError, match=r"was trained with another config; resume with the same --config"):
        train(TrainConfig(), out, None, workers=1, resume=True)
    with open(out / "log.csv", "ab") as f:  # a kill after a stage's row, before its state; then a cut line
        f.write(b"ppo0,9,9,9\nppo0,9,")
    second = train(TINY, out, None, workers=1, seed=3, resume=True)
    assert [r["stage"] for r in second.stages] == ["baseline", "dagger0", "ppo0"]
    log = _rows(out / "log.csv")
    assert [r["stage"] for r in log] == ["baseline", "dagger0", "ppo0"] and list(log[0]) == LOG_COLUMNS
    assert [r["stage"] for r in _rows(out / "stages.csv")] == ["baseline", "dagger0", "ppo0"]
    state = torch.load(out / "state.pt", weights_only=True)
    assert state["state"]["stage"] == 3 and state["state"]["episodes"] == 2
    policy = load_policy(out / "policy.npz")
    assert policy.meta["meta"]["stage"] == second.best_stage


def test_policy_search_moves_the_edge_weights_to_its_elites_and_resumes(tmp_path: Path) -> None:
    from dataclasses import replace

    cfg = replace(TINY, search_generations=2, search_population=3, search_elites=1, search_episodes=1)
    cfg = replace(cfg, dagger_rounds=0, ppo_iterations=0)
    out = tmp_path / "run"
    first = train(cfg, out, None, episodes=3, workers=1, seed=5)  # the budget holds one generation
    assert [r["stage"] for r in first.stages] == ["baseline", "search0"]
    state = torch.load(out / "state.pt", weights_only=True)
    assert state["state"]["episodes"] == 3 and len(state["state"]["search_sigma"]) == 5
    w0 = state["net"]["edge_head.weight"][0].tolist()
    log = _rows(out / "log.csv")
    # one elite: the next weights are exactly the winning candidate's, and the log says which
    assert [float(v) for v in log[1]["edge_weights"].split()] == pytest.approx(w0, abs=1e-3)
    assert float(log[1]["search_best_steps"]) <= float(log[1]["steps_mean"])  # the current mean was a candidate
    assert all(s == 0.5 for s in state["state"]["search_sigma"])  # one elite has no spread: the floor
    second = train(cfg, out, None, workers=1, seed=5, resume=True)
    assert [r["stage"] for r in second.stages] == ["baseline", "search0", "search1"]
    assert torch.load(out / "state.pt", weights_only=True)["state"]["episodes"] == 6
    kept = load_policy(out / "policy.npz")
    assert kept.meta["meta"]["stage"] == second.best_stage


def test_relative_score_is_against_the_heuristic_and_picks_the_stage_kept(tmp_path: Path) -> None:
    from dataclasses import replace

    cfg = replace(TINY, search_generations=2, search_population=3, search_elites=1, search_episodes=1)
    cfg = replace(cfg, dagger_rounds=0, ppo_iterations=0, val_maps=2, score="relative")
    run = train(cfg, tmp_path / "run", None, workers=1, seed=5)
    scores = [r["val_score"] for r in run.stages]
    assert [r["stage"] for r in run.stages] == ["baseline", "search0", "search1"]
    assert scores[0] == 1.0  # the heuristic against itself
    assert run.best_stage == run.stages[min(range(3), key=lambda i: (scores[i], i))]["stage"]
    assert [float(r["val_score"]) for r in _rows(tmp_path / "run" / "stages.csv")] == pytest.approx(scores)
    with pytest.raises(MrExploreError, match=r"score must be 'steps' or 'relative', got 'ratio'"):
        replace(cfg, score="ratio")


def test_validate_policy_gives_steps_to_the_end_and_to_99_per_map_in_order() -> None:
    from dataclasses import replace

    from mrexplore.training.trainer import FRESH_SEED0, validate_policy

    maps = [f"varied:{FRESH_SEED0 + i}" for i in (1, 0)]
    got_maps, steps, cov = validate_policy(
        None, replace(TINY, episodes=replace(TINY_EPISODES, max_steps=400)), None, workers=2, maps=maps
    )
    assert got_maps == maps and steps.shape == (2, 2) and cov.shape == (2,)
    assert (steps[1] <= steps[0]).all() and (cov >= 0.99).all()  # both explored: 99% comes before the end
    # an episode's seed is its position: the first map alone runs the same episode again
    alone = validate_policy(
        None, replace(TINY, episodes=replace(TINY_EPISODES, max_steps=400)), None, workers=1, maps=maps[:1]
    )[1]
    assert alone[:, 0].tolist() == steps[:, 0].tolist()


def test_validation_comes_back_in_the_maps_order_whatever_finishes_first(monkeypatch: pytest.MonkeyPatch) -> None:
    # Workers hand results back as they finish; a runner that hands them back last first stands in for that.
    from dataclasses import replace

    from mrexplore.training import trainer as tr
    from mrexplore.training.episodes import run_job

    def last_first(self: object, jobs: list, deadline: float) -> Iterator[dict]:
        yield from reversed([run_job(j) for j in jobs])

    monkeypatch.setattr(tr._Runner, "run", last_first)
    cfg = replace(TINY, episodes=replace(TINY_EPISODES, max_steps=400))
    maps = [f"varied:{tr.FRESH_SEED0 + i}" for i in (0, 1)]
    steps = tr.validate_policy(None, cfg, None, workers=1, maps=maps)[1]
    alone = tr.validate_policy(None, cfg, None, workers=1, maps=maps[:1])[1]  # the same first episode
    assert steps[0, 0] != steps[0, 1]  # 214 and 120 steps: an order mixed up would show
    assert alone[:, 0].tolist() == steps[:, 0].tolist()


def test_validation_episodes_have_the_configured_team(monkeypatch: pytest.MonkeyPatch) -> None:
    from dataclasses import replace

    from mrexplore.training import trainer
    from mrexplore.training.episodes import EpisodeJob

    teams: list[int] = []

    def results(self: object, jobs: list[EpisodeJob], timeout: float) -> list[dict[str, float]]:
        teams.extend(j.robots for j in jobs)
        return [{"steps": 10, "steps_99": 8, "coverage": 1.0} for _ in jobs]

    monkeypatch.setattr(trainer._Runner, "results", results)
    maps = ["varied:1", "varied:2"]
    trainer.validate_policy(None, TINY, None, maps=maps)
    trainer.validate_policy(None, replace(TINY, val_robots=2), None, maps=maps)
    assert teams == [3, 3, 2, 2]  # the default is the dev set's Table I team
    with pytest.raises(MrExploreError, match="val_robots must be >= 1, got 0"):
        replace(TINY, val_robots=0)


def test_a_budget_under_one_search_generation_skips_the_search(tmp_path: Path) -> None:
    from dataclasses import replace

    said: list[str] = []
    cfg = replace(TINY, search_generations=1, search_population=3, search_elites=1, ppo_iterations=0)
    run = train(cfg, tmp_path / "run", None, episodes=2, workers=1, seed=5, say=said.append)
    assert [r["stage"] for r in run.stages] == ["baseline", "dagger0"]
    assert "2 episodes left, under a search generation's 3; skipping search0" in said


def test_nothing_to_resume(tmp_path: Path) -> None:
    with pytest.raises(MrExploreError, match=r"nothing to resume in .* \(no state.pt\); drop --resume"):
        train(TINY, tmp_path, None, resume=True)


def test_validation_maps_are_held_out(tmp_path: Path) -> None:
    folder = tmp_path / "dungeon"
    folder.mkdir()
    for i in range(40):
        (folder / f"train_{i:03d}.png").write_bytes(b"")
    train_maps, val = split_maps(tmp_path, 6)
    assert len(train_maps) == 37 and not set(train_maps) & set(val)
    assert val[:3] == [str(folder / f"train_{i:03d}.png") for i in (37, 38, 39)]
    assert val[3:] == ["varied:1000000", "varied:1000001", "varied:1000002"]
    fixed = split_maps(tmp_path, 6, "generated")[1][3:]
    assert fixed == ["generated:1000000", "generated:1000001", "generated:1000002"]


def test_training_episodes_take_the_run_settings_and_keep_faults_inside_the_team() -> None:
    from mrexplore.config import FaultConfig, MissionConfig, SensorConfig, SimConfig
    from mrexplore.training.episodes import EpisodeJob, JobKind, episode_mission, hier_pipeline

    faults = FaultConfig(robot_failures=((0, 50), (3, 20)), message_loss=0.2)
    job = EpisodeJob(
        JobKind.EVAL,
        "generated:2",
        2,
        0,
        None,
        TrainConfig(episodes=EpisodesConfig(resolution_m=0.2, max_steps=77)),
        sim=SimConfig(sensor=SensorConfig(range_m=4.0)),
        mission=MissionConfig(faults=faults),
    )
    m = episode_mission(job, hier_pipeline(None))
    assert m.mission_cfg.max_steps == 77 and m.sim_cfg.robots == 2 and m.sim_cfg.sensor.range_m == 4.0
    assert m.mission_cfg.faults.robot_failures == ((0, 50),)  # robot 3 is not in a team of 2
    assert m.mission_cfg.faults.message_loss == 0.2


NCM_TINY = TrainConfig(
    strategy="ncm",
    episodes=replace(TINY_EPISODES, max_steps=120),
    val_maps=1,
    ncm=NcmTrainConfig(ppo_iterations=2, ppo_episodes=1, ppo_epochs=1),
)


def test_ncm_trains_with_the_same_stages_logs_and_resume(tmp_path: Path) -> None:
    from mrexplore.training.checkpoint import load_ncm_policy

    out = tmp_path / "ncm"
    first = train(NCM_TINY, out, None, episodes=1, workers=1, seed=5)
    assert [r["stage"] for r in first.stages] == ["baseline", "ppo0"]
    second = train(NCM_TINY, out, None, workers=1, seed=5, resume=True)
    assert [r["stage"] for r in second.stages] == ["baseline", "ppo0", "ppo1"]
    log = _rows(out / "log.csv")
    assert [r["stage"] for r in log] == ["baseline", "ppo0", "ppo1"]
    assert all(r["kl"] and r["entropy"] and r["value_loss"] and r["return_mean"] for r in log[1:])
    assert all(float(r["val_sampled_steps_mean"]) > 0 and float(r["val_steps_mean"]) > 0 for r in log)
    policy = load_ncm_policy(out / "policy.npz")  # the actor alone; the critic stays in state.pt
    assert policy.meta["meta"]["stage"] == second.best_stage
    assert policy.meta["meta"]["chosen_by"] == "val_sampled_steps_mean"  # NCM's own evaluation samples
    best = min(second.stages, key=lambda r: r["val_sampled_steps_mean"])["val_sampled_steps_mean"]
    assert policy.meta["meta"]["val_sampled_steps_mean"] == best
    assert not any(k.startswith("critic") for k in policy.net.state_dict())
    with pytest.raises(
        MrExploreError,
        match=r"is for the ncm strategy, not hier; pass one written by .mrexplore train --strategy hier.",
    ):
        load_policy(out / "policy.npz")


@pytest.mark.slow
def test_ncm_trains_through_ray_as_through_processes(tmp_path: Path) -> None:
    pytest.importorskip("ray", reason="Ray is the optional scale-out path: pip install 'mrexplore[ray]'")
    local = train(NCM_TINY, tmp_path / "procs", None, episodes=1, workers=2, seed=5)
    on_ray = train(NCM_TINY, tmp_path / "ray", None, episodes=1, workers=2, seed=5, ray_address="local")
    keys = ("stage", "val_steps_mean", "val_sampled_steps_mean")
    assert [[r[k] for k in keys] for r in on_ray.stages] == [[r[k] for k in keys] for r in local.stages]


def test_ncm_rewards_sum_to_its_area_formula() -> None:
    """NCM's reward per decision of k steps is 5e-3 * (new m^2 - 4 k / 25); over an episode the rewards
    sum to the same formula over the whole span from the first decision to the end."""

    from mrexplore.training.episodes import EpisodeJob, JobKind, _run_ncm, weights_of
    from mrexplore.training.ncm_net import NcmActorCritic

    torch.manual_seed(0)
    net = NcmActorCritic()
    job = EpisodeJob(JobKind.PPO, "generated:4", 2, 9, weights_of(net), NCM_TINY)
    out = _run_ncm(job, net.eval())
    rec, rewards = out["steps_rec"], out["rewards"]
    assert len(rec) == len(rewards) == len(out["discounts"]) == out["decisions"] > 1
    assert all(0 < d <= 1 for d in out["discounts"][:-1])
    # the same episode again, counting area and steps from the first decision on
    from mrexplore.global_planning.learned.ncm_planner import NcmPlanner
    from mrexplore.training.episodes import episode_mission, ncm_pipeline

    planner = NcmPlanner(net.actor, sample=True)
    m = episode_mission(job, ncm_pipeline(planner))
    first: tuple[int, int] | None = None
    while m.advance():
        if m.pose() is None:
            continue
        first = first or (m.sim.known_cells, m.steps)
        m.commit()
    area_m2 = (m.sim.known_cells - first[0]) * 0.2**2
    assert m.steps == out["steps"]
    assert rewards.sum() == pytest.approx(5e-3 * (area_m2 - 4 * (m.steps - first[1]) / 25), rel=1e-9)


def test_a_policy_that_reads_the_predicted_gain_trains_searches_six_weights_and_explores(tmp_path: Path) -> None:
    from dataclasses import replace

    from mrexplore.config import LearnedConfig
    from mrexplore.pipeline import make_strategy

    cfg = replace(TINY, search_generations=1, search_population=2, search_elites=1, search_episodes=1)
    cfg = replace(cfg, dagger_rounds=1, ppo_iterations=0, learned=LearnedConfig(use_predicted_gain=True))
    run = train(cfg, tmp_path / "run", None, workers=1, seed=2, predictor="none")
    assert [r["stage"] for r in run.stages] == ["baseline", "search0", "dagger0"]
    policy = load_policy(run.policy_path)
    assert len(policy.net.edge_weights) == 6 and policy.net.cfg.use_predicted_gain
    assert policy.meta["meta"]["predictor"] == {"path": "none", "sha256": ""}
    hier = make_strategy("hier", policy=str(run.policy_path), predictor="none")
    assert hier.predictor == {"path": "none", "sha256": ""} and hier.planner.predictor is None
    assert make_strategy("hier").predictor is None  # the shipped policy reads no prediction


def test_a_policy_that_reads_the_predicted_shortcut_trains_and_explores(tmp_path: Path) -> None:
    from dataclasses import replace

    from mrexplore.config import LearnedConfig, MapConfig, SimConfig
    from mrexplore.maps.loaders import load_map
    from mrexplore.mission import MissionSpec, run_mission
    from mrexplore.pipeline import make_strategy

    cfg = replace(TINY, search_generations=1, search_population=2, search_elites=1, search_episodes=1)
    cfg = replace(cfg, dagger_rounds=0, ppo_iterations=0, learned=LearnedConfig(use_predicted_path=True))
    run = train(cfg, tmp_path / "run", None, workers=1, seed=2, predictor="none")
    policy = load_policy(run.policy_path)
    assert len(policy.net.edge_weights) == 6 and policy.net.cfg.use_predicted_path
    assert not policy.net.cfg.use_predicted_gain
    hier = make_strategy("hier", policy=str(run.policy_path), predictor="none")
    assert hier.predictor == {"path": "none", "sha256": ""}
    out = run_mission(MissionSpec(load_map("generated:3", MapConfig(resolution_m=0.2)), hier, SimConfig(robots=2)))
    assert out.measures.coverage > 0.9
