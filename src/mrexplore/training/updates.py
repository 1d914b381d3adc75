"""The trainer's updates of the network: listwise imitation of the expert's labels, PPO epochs (``hier``'s
and NeuralCoMapping's losses over one loop), and their optimisers. The maths are pure functions in
:mod:`~mrexplore.training.ppo`."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import torch

from mrexplore.config import TrainConfig
from mrexplore.training.episodes import NcmActorCritic
from mrexplore.training.expert import ExpertLabel
from mrexplore.training.hier_net import MultiGraphNet, collate
from mrexplore.training.ncm_net import NcmStep, ncm_collate, ncm_log_prob
from mrexplore.training.ppo import PPOStats, gae, listwise_loss, ppo_loss
from mrexplore.training.sequential import PolicyStep, assignment_score, sequential_log_prob

__all__ = ["fit_imitation", "imitation_loss", "hier_ppo_update", "ncm_ppo_update", "optimizer"]

BATCH = 64
"""Minibatch size of every update."""


def _pad_rows(rows: Sequence[np.ndarray], width: int, fill: float) -> np.ndarray:
    out = np.full((len(rows), width), fill, dtype=np.asarray(rows[0]).dtype)
    for i, r in enumerate(rows):
        out[i, : len(r)] = r
    return out


def _label_batch(labels: Sequence[ExpertLabel]) -> tuple[Any, torch.Tensor, torch.Tensor, torch.Tensor]:
    batch = collate([lab.inputs for lab in labels])
    R = batch.robots.shape[1]
    M = max(len(lab.candidates) for lab in labels)
    cands = np.full((len(labels), M, R), -1, np.int64)
    rets = np.zeros((len(labels), M))
    valid = np.zeros((len(labels), M), bool)
    for b, lab in enumerate(labels):
        m, r = lab.candidates.shape
        cands[b, :m, :r] = lab.candidates
        rets[b, :m] = lab.returns
        valid[b, :m] = True
    return batch, torch.from_numpy(cands), torch.from_numpy(rets).float(), torch.from_numpy(valid)


def imitation_loss(
    net: MultiGraphNet, labels: Sequence[ExpertLabel], temperature: float, residual_l2: float = 0.0
) -> tuple[torch.Tensor, float]:
    """Listwise loss of a minibatch (plus ``residual_l2`` times the mean squared residual over the allowed
    pairs) and the share of decisions where the student ranks the expert's best candidate (or one as good)
    first."""
    batch, cands, rets, valid = _label_batch(labels)
    aff, _, _ = net(batch)
    scores = assignment_score(aff, cands)
    loss = listwise_loss(scores, rets, valid, temperature)
    if residual_l2 > 0:
        # the scoring MLP's part only: the linear edge path is the policy search's, which this must not undo
        allowed = torch.isfinite(aff)
        residual = torch.where(allowed, aff - batch.base - net.edge_path(batch), torch.zeros_like(aff))
        loss = loss + residual_l2 * (residual**2).sum() / allowed.sum().clamp(min=1)
    with torch.no_grad():
        pick = torch.where(valid, scores, torch.full_like(scores, -1e9)).argmax(-1)
        best = torch.where(valid, rets, torch.full_like(rets, -1e9)).max(-1).values
        agree = float((rets.gather(1, pick[:, None]).squeeze(1) >= best - 1e-9).float().mean())
    return loss, agree


def fit_imitation(
    net: MultiGraphNet,
    opt: torch.optim.Optimizer,
    data: Sequence[ExpertLabel],
    cfg: TrainConfig,
    rng: np.random.Generator,
) -> tuple[float, float]:
    net.train()
    losses, agrees = [], []
    for _ in range(cfg.imitation_epochs):
        order = rng.permutation(len(data))
        for s in range(0, len(order), BATCH):
            batch = [data[i] for i in order[s : s + BATCH]]
            loss, agree = imitation_loss(net, batch, cfg.return_temperature, cfg.residual_l2)
            opt.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(net.parameters(), 1.0)
            opt.step()
            losses.append(float(loss.detach()))
            agrees.append(agree)
    net.eval()
    last = max(1, len(losses) // max(1, cfg.imitation_epochs))  # the last epoch's batches
    return float(np.mean(losses[-last:])), float(np.mean(agrees[-last:]))


def _ppo_epochs(
    net: torch.nn.Module,
    opt: torch.optim.Optimizer,
    trajectories: Sequence[dict[str, Any]],
    reward_scale: float,
    gae_lambda: float,
    epochs: int,
    rng: np.random.Generator,
    minibatch_loss: Callable[[list[Any], torch.Tensor, torch.Tensor], tuple[torch.Tensor, PPOStats]],
) -> dict[str, float]:
    """PPO epochs over the decisions of ``trajectories`` (each with ``steps_rec``, whose steps carry the
    critic's ``value``; ``rewards``; ``discounts``): GAE per episode, advantages normalised over the batch,
    minibatches of 64 in a random order; ``minibatch_loss(steps, advantages, returns)`` is the strategy's
    loss. Returns the mean of each logged part."""
    steps: list[Any] = []
    adv_all, ret_all = [], []
    for tr in trajectories:
        rec = tr["steps_rec"]
        if not rec:
            continue
        values = np.array([s.value for s in rec])
        adv, ret = gae(tr["rewards"] * reward_scale, values, tr["discounts"], 0.0, gae_lambda)
        steps += rec
        adv_all.append(adv)
        ret_all.append(ret)
    if not steps:
        return {}
    adv = np.concatenate(adv_all)
    adv = (adv - adv.mean()) / (adv.std() + 1e-8)
    ret = np.concatenate(ret_all)
    net.train()
    stats: list[dict[str, float]] = []
    for _ in range(epochs):
        order = rng.permutation(len(steps))
        for s in range(0, len(order), BATCH):
            idx = order[s : s + BATCH]
            t = torch.from_numpy
            loss, st = minibatch_loss([steps[i] for i in idx], t(adv[idx]).float(), t(ret[idx]).float())
            opt.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(net.parameters(), 1.0)
            opt.step()
            stats.append(
                {
                    "loss": float(loss.detach()),
                    "kl": st.approx_kl,
                    "clip_fraction": st.clip_fraction,
                    "entropy": st.entropy,
                    "value_loss": st.value,
                }
            )
    net.eval()
    return {k: float(np.mean([x[k] for x in stats])) for k in stats[0]}


def hier_ppo_update(
    net: MultiGraphNet,
    opt: torch.optim.Optimizer,
    trajectories: Sequence[dict[str, Any]],
    data: Sequence[ExpertLabel],
    cfg: TrainConfig,
    rng: np.random.Generator,
) -> dict[str, float]:
    """hier's PPO on eq. 9 (sequential sampling's log-probability), with the listwise expert loss kept."""

    def minibatch_loss(mb: list[PolicyStep], adv: torch.Tensor, ret: torch.Tensor) -> tuple[torch.Tensor, PPOStats]:
        batch = collate([st.inputs for st in mb])
        R = batch.robots.shape[1]
        aff, vr, vc = net(batch)
        v_new = net.value_of(vr, vc, batch, torch.from_numpy(np.stack([x.extra for x in mb])))
        o = torch.from_numpy(_pad_rows([st.order for st in mb], R, -1))
        c = torch.from_numpy(_pad_rows([st.choices for st in mb], R, -1))
        logp, ent = sequential_log_prob(aff, o, c)
        old = torch.tensor([x.logp for x in mb], dtype=torch.float32)
        loss, st = ppo_loss(logp, old, adv, v_new, ret, ent, cfg.clip, cfg.value_coef, cfg.entropy_coef)
        if data and cfg.imitation_coef > 0:
            pick = rng.choice(len(data), size=min(BATCH, len(data)), replace=False)
            im, _ = imitation_loss(net, [data[i] for i in pick], cfg.return_temperature, cfg.residual_l2)
            loss = loss + cfg.imitation_coef * im
        return loss, st

    return _ppo_epochs(net, opt, trajectories, cfg.reward_scale, cfg.gae_lambda, cfg.ppo_epochs, rng, minibatch_loss)


def ncm_ppo_update(
    net: NcmActorCritic,
    opt: torch.optim.Optimizer,
    trajectories: Sequence[dict[str, Any]],
    cfg: TrainConfig,
    rng: np.random.Generator,
) -> dict[str, float]:
    """NCM's PPO: per-robot categoricals' joint log-probability, its critic, its coefficients (rewards
    already carry NCM's scale)."""
    n = cfg.ncm

    def minibatch_loss(mb: list[NcmStep], adv: torch.Tensor, ret: torch.Tensor) -> tuple[torch.Tensor, PPOStats]:
        logp, ent = ncm_log_prob(net.actor, mb)
        v_new = net.critic(ncm_collate([x.inputs for x in mb]), torch.from_numpy(np.stack([x.extra for x in mb])))
        old = torch.tensor([x.logp for x in mb], dtype=torch.float32)
        return ppo_loss(logp, old, adv, v_new, ret, ent, n.clip, n.value_coef, n.entropy_coef)

    return _ppo_epochs(net, opt, trajectories, 1.0, n.gae_lambda, n.ppo_epochs, rng, minibatch_loss)


def optimizer(net: MultiGraphNet | NcmActorCritic, cfg: TrainConfig) -> torch.optim.Optimizer:
    if isinstance(net, NcmActorCritic):
        return torch.optim.Adam(
            [
                {"params": net.actor.parameters(), "lr": cfg.ncm.lr},
                {"params": net.critic.parameters(), "lr": cfg.ncm.lr * cfg.ncm.critic_lr_ratio},
            ]
        )
    return torch.optim.Adam(net.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)


# -- the run ----------------------------------------------------------------------------------------------
