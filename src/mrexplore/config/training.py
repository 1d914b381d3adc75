"""Training's settings: how episodes are drawn, the learned global layer's recipe (search, imitation, PPO),
NeuralCoMapping's PPO, and the map predictor's training."""

from __future__ import annotations

from dataclasses import dataclass, field

from mrexplore.config.planning import LearnedConfig
from mrexplore.config.schema import Checked, Interval, OneOf, at_least, non_negative, positive
from mrexplore.types import MrExploreError

__all__ = ["EpisodesConfig", "NcmTrainConfig", "TRAINABLE", "TrainConfig", "PredictorTrainConfig"]


@dataclass(frozen=True)
class EpisodesConfig(Checked):
    """How training draws its episodes, shared by the policy's and the map predictor's training: each episode
    is on a procedural floor plan or a training DungeonMap, with a team drawn between two sizes."""

    resolution_m: float = 0.1
    """Cell size of the episodes' maps, metres."""
    robots_min: int = 2
    """Fewest robots of an episode."""
    robots_max: int = 5
    """Most robots of an episode."""
    max_steps: int = 1500
    """Step budget of an episode."""
    generated_share: float = 0.5
    """Share of episodes on procedural floor plans (the rest on training DungeonMaps)."""
    plans: str = "varied"
    """Procedural floor plans of training and validation: ``varied`` (``varied:SEED``, whose size, outline,
    rooms, corridor, doors and clutter the seed draws, spread like HouseExpo's: ``benchmarks/plan_stats.py``)
    or ``generated`` (``generated:SEED``, the 16 x 12 m built-in plan)."""

    _constraints = {
        "resolution_m": positive("metres"),
        "robots_min": at_least(1),
        "robots_max": at_least("robots_min"),
        "max_steps": at_least(1),
        "generated_share": Interval(0, 1),
        "plans": OneOf(("varied", "generated")),
    }


@dataclass(frozen=True)
class NcmTrainConfig(Checked):
    """PPO of the NeuralCoMapping baseline, with its public code's settings (Ye, Dong et al., CVPR 2022)."""

    ppo_iterations: int = 40
    """PPO iterations (stages ppo0...)."""
    ppo_episodes: int = 8
    """Episodes collected per iteration."""
    ppo_epochs: int = 4
    """Passes over a batch."""
    lr: float = 5e-4
    """Adam learning rate of the actor."""
    critic_lr_ratio: float = 1.0
    """The critic's learning rate is the actor's times this. NCM's is 0.05 for its CNN critic over the maps;
    ours (:class:`~mrexplore.training.ncm_net.NcmCritic`) is a small MLP, which at 0.05
    would barely move from its start in a run of this project's length."""
    gamma: float = 0.99
    """Discount per 25 simulation steps (NCM's decision; a decision of k steps discounts by gamma^(k/25))."""
    gae_lambda: float = 0.95
    """GAE tau."""
    clip: float = 0.2
    """PPO ratio clip."""
    value_coef: float = 3.0
    """Weight of the value loss."""
    entropy_coef: float = 1e-4
    """Weight of the entropy bonus."""
    area_reward: float = 5e-3
    """Reward per newly explored m^2."""
    area_offset_m2: float = 4.0
    """m^2 subtracted from a 25-step decision's new area (in proportion for other lengths)."""
    select: str = "sampled"
    """Which validation keeps a checkpoint (both are logged): ``sampled`` (NCM's own evaluation, each robot
    drawing its node; seeded, so repeatable) or ``argmax``. A PPO policy is trained as a sampler, and its
    argmax decoding can lag the untrained network's while its sampled episodes improve."""

    _constraints = {
        "ppo_iterations": at_least(1),
        "ppo_episodes": at_least(1),
        "ppo_epochs": at_least(1),
        "lr": positive(),
        "critic_lr_ratio": positive(),
        "gamma": Interval(0, 1, "right"),
        "gae_lambda": Interval(0, 1),
        "clip": positive(),
        "value_coef": non_negative(),
        "entropy_coef": non_negative(),
        "area_reward": positive(),
        "area_offset_m2": non_negative(),
        "select": OneOf(("sampled", "argmax")),
    }


TRAINABLE = ("hier", "ncm")
"""Strategies ``mrexplore train`` trains."""


@dataclass(frozen=True)
class TrainConfig(Checked):
    """Training of a learned global layer: for ``hier``, imitation of a lookahead expert (DAgger), then PPO
    on eq. 9; for ``ncm``, NeuralCoMapping's PPO (:class:`NcmTrainConfig`). Both share the map split,
    episode settings, validation and checkpoints."""

    strategy: str = "hier"
    """What is trained: ``hier`` (the paper's mGNN) or ``ncm`` (the NeuralCoMapping baseline)."""
    learned: LearnedConfig = field(default_factory=LearnedConfig)
    ncm: NcmTrainConfig = field(default_factory=NcmTrainConfig)
    episodes: EpisodesConfig = field(default_factory=EpisodesConfig)
    """How training and validation episodes are drawn (maps, teams, cell size, step budget)."""
    val_maps: int = 64
    """Validation episodes per evaluation: half held-out training DungeonMaps, half held-out floor plans.
    Too few let a stage win validation by chance."""
    val_robots: int = 3
    """Robots in every validation episode: the team of the dev set's Table I (training draws
    ``episodes.robots_min`` to ``episodes.robots_max``)."""
    score: str = "steps"
    """How the policy search ranks its vectors and validation picks the stage kept: ``steps`` (mean steps
    to the end, the largest maps weighing most) or ``relative`` (every episode weighing the same: the
    geometric mean over episodes of its steps to the end plus to 99% coverage, over those of the
    generation's current weights in the search and of the heuristic in validation; see
    :func:`~mrexplore.training.search.relative_score`)."""
    # -- policy search on the linear edge path (cross-entropy method)
    search_generations: int = 6
    """Generations of the cross-entropy search over the residual's linear edge weights (one per edge
    feature), before imitation: each draws ``search_population`` weight vectors around the current
    ones (the current ones among them), runs every vector on the same ``search_episodes`` training
    episodes, and moves to the mean and spread of the ``search_elites`` that score best (``score``)."""
    search_population: int = 8
    """Weight vectors tried per generation (the current mean is one of them)."""
    search_elites: int = 3
    """Vectors with the best score (fewest mean steps by default) that set the next mean and spread."""
    search_episodes: int = 48
    """Training episodes each vector of a generation runs (the same ones for every vector)."""
    search_sigma: float = 5.0
    """Spread of the first generation, per weight (a weight of 5 on the isolation feature, in tenths of
    metres, offers an isolated cluster 0.5 m nearer per metre to its nearest other cluster)."""
    search_sigma_min: float = 0.5
    """The spread never falls below this (keeps a noisy ranking from freezing the search)."""
    # -- imitation of the lookahead expert
    dagger_rounds: int = 2
    """Rounds of (collect on the student's own states, fit); round 0's student is the policy the
    search left (the heuristic when it ran none)."""
    episodes_per_round: int = 10
    """Training episodes collected per DAgger round."""
    label_every: int = 4
    """Every this many decisions of an episode the expert labels (the others just move it on)."""
    horizon_steps: int = 400
    """Each expert candidate is run this many simulation steps forward. Short horizons are myopic:
    candidates that grab open area and leave pockets behind rank first."""
    expert_world: str = "truth"
    """Where the expert runs its candidates forward: ``truth`` (the simulator's map, scored by eq. 9's
    return over ``horizon_steps``) or ``known`` (the world the team has observed, every unseen cell a
    wall, scored by minus the steps until no frontier is left; labels a student could learn from what it
    sees: :func:`~mrexplore.training.expert.known_world_returns`)."""
    noisy_candidates: int = 4
    """Noisy utility assignments among the expert's candidates."""
    noise_m: float = 4.0
    """Gumbel scale of the noise on the utility cost of noisy candidates, metres of detour."""
    return_temperature: float = 10.0
    """Target of the listwise loss: softmax(candidate return / this)."""
    imitation_epochs: int = 8
    """Passes over the aggregated expert data per round (too many overfit single-rollout labels)."""
    lr: float = 1e-3
    """Adam learning rate of imitation."""
    weight_decay: float = 1e-4
    """Adam weight decay."""
    residual_l2: float = 0.01
    """Weight of the mean squared residual in the imitation loss: the network departs from the heuristic
    only where the expert's data insist."""
    # -- PPO on eq. 9
    ppo_iterations: int = 0
    """PPO iterations after imitation (none in the shipped recipe: its sampled policy explores worse than
    the decoded one, and no PPO iteration has beaten the best imitation stage on validation)."""
    ppo_episodes: int = 12
    """Episodes collected per PPO iteration."""
    ppo_epochs: int = 4
    """Passes over a PPO batch."""
    ppo_lr: float = 3e-4
    """Adam learning rate of PPO."""
    gamma: float = 0.995
    """Discount per simulation step (a decision spanning k steps discounts by gamma^k)."""
    gae_lambda: float = 0.95
    """GAE lambda."""
    clip: float = 0.2
    """PPO ratio clip."""
    value_coef: float = 0.5
    """Weight of the value loss."""
    entropy_coef: float = 0.01
    """Weight of the entropy bonus."""
    reward_scale: float = 0.01
    """Rewards of eq. 9 are multiplied by this for the critic's sake."""
    imitation_coef: float = 1.0
    """Weight of the listwise expert loss kept during PPO on the aggregated data (keeps the policy near
    the expert while RL fine-tunes)."""

    _constraints = {
        "strategy": OneOf(TRAINABLE),
        "val_maps": at_least(1),
        "val_robots": at_least(1),
        "score": OneOf(("steps", "relative")),
        "search_generations": non_negative(),
        "search_population": at_least(2),
        "search_elites": Interval(1, "search_population"),
        "search_episodes": at_least(1),
        "search_sigma": positive(),
        "search_sigma_min": positive(),
        "dagger_rounds": non_negative(),
        "episodes_per_round": at_least(1),
        "label_every": at_least(1),
        "horizon_steps": at_least(1),
        "expert_world": OneOf(("truth", "known")),
        "noisy_candidates": non_negative(),
        "noise_m": positive(),
        "return_temperature": positive(),
        "imitation_epochs": at_least(1),
        "lr": positive(),
        "weight_decay": non_negative(),
        "residual_l2": non_negative(),
        "ppo_iterations": non_negative(),
        "ppo_episodes": at_least(1),
        "ppo_epochs": at_least(1),
        "ppo_lr": positive(),
        "gamma": Interval(0, 1, "right"),
        "gae_lambda": Interval(0, 1),
        "clip": positive(),
        "value_coef": non_negative(),
        "entropy_coef": non_negative(),
        "reward_scale": positive(),
        "imitation_coef": non_negative(),
    }


@dataclass(frozen=True)
class PredictorTrainConfig(Checked):
    """The learned map predictor and its training (``mrexplore train --target predictor``): the team's belief taken
    at random decisions of missions on the training maps (never the dev maps), the ground truth as the label;
    the loss and the scores count the unknown cells near a frontier."""

    cell_m: float = 0.2
    """Side of the predictor's cells, metres: the belief is pooled onto them (0.1 m planning cells two by
    two) and the prediction repeated back onto the planning cells."""
    width: int = 8
    """Channels of the U-Net's finest level (doubled at each of its two coarser levels)."""
    episodes: EpisodesConfig = field(default_factory=lambda: EpisodesConfig(robots_min=1))
    """How collection and validation missions are drawn (maps, teams, cell size, step budget)."""
    collector: str = "hier-heuristic"
    """Strategy of the collection missions (whose beliefs the predictor learns to complete)."""
    missions: int = 480
    """Training missions collected, each on a training DungeonMap or a procedural plan."""
    val_missions: int = 48
    """Validation missions: half on held-out training DungeonMaps, half on held-out procedural plans."""
    moments: int = 4
    """Beliefs kept per mission, drawn at random among its decisions within the coverage range."""
    min_coverage: float = 0.1
    """Beliefs are drawn from decisions with at least this coverage."""
    max_coverage: float = 0.9
    """... and at most this coverage."""
    band_m: float = 6.0
    """The loss and the validation scores count the unknown cells within this distance of a frontier."""
    crop_cells: int = 64
    """Side of a training crop, predictor cells (a multiple of 4), around a random cell of the band."""
    batch: int = 32
    """Crops per gradient step."""
    epochs: int = 60
    """Epochs at most (the minutes budget may stop it first); the epoch of least validation loss is kept."""
    steps_per_epoch: int = 200
    """Gradient steps per epoch, each on fresh random crops."""
    lr: float = 2e-3
    """Adam learning rate."""
    weight_decay: float = 1e-5
    """Adam weight decay."""

    _constraints = {
        "cell_m": positive("metres"),
        "width": Interval(1, 256),
        "collector": OneOf(("hier-heuristic", "utility", "nearest")),
        "missions": at_least(1),
        "val_missions": at_least(1),
        "moments": at_least(1),
        "min_coverage": Interval(0, 1),
        "max_coverage": Interval("min_coverage", 1),
        "band_m": positive("metres"),
        "crop_cells": at_least(8),
        "batch": at_least(1),
        "epochs": at_least(1),
        "steps_per_epoch": at_least(1),
        "lr": positive(),
        "weight_decay": non_negative(),
    }

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.crop_cells % 4:
            raise MrExploreError(f"crop_cells must be a multiple of 4, got {self.crop_cells}")
