"""The policy's distribution and decoding: exact log-probabilities against enumeration, sampling
frequencies, Hungarian decoding with unequal counts, the summed affinity of candidates."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import torch

from mrexplore.global_planning.learned.policy import hungarian_decode, sample_sequential
from mrexplore.training.sequential import assignment_score, sequential_log_prob

AFF = np.array([[1.0, 0.0, -1.0], [0.5, 2.0, 0.0], [0.0, 0.3, 0.7]])


def _prob_by_hand(aff: np.ndarray, order: list[int], choices: list[int]) -> float:
    """Each robot in turn: softmax over the clusters not yet taken."""
    taken: set[int] = set()
    p = 1.0
    for i in order:
        free = [k for k in range(aff.shape[1]) if k not in taken and np.isfinite(aff[i, k])]
        z = sum(math.exp(aff[i, k]) for k in free)
        p *= math.exp(aff[i, choices[i]]) / z
        taken.add(choices[i])
    return p


def test_log_prob_matches_enumeration_on_3x3() -> None:
    order = [2, 0, 1]
    total = 0.0
    for perm in itertools.permutations(range(3)):
        choices = list(perm)  # robot i takes cluster perm[i]
        lp, _ = sequential_log_prob(torch.tensor(AFF[None]), torch.tensor([order]), torch.tensor([choices]))
        assert float(lp[0]) == pytest.approx(math.log(_prob_by_hand(AFF, order, choices)), abs=1e-9)
        total += math.exp(float(lp[0]))
    assert total == pytest.approx(1.0)  # one cluster per robot: the six matchings carry all the mass


def test_sampler_frequencies_and_log_prob_agree_with_the_batched_one() -> None:
    rng = np.random.default_rng(0)
    counts: dict[tuple[int, ...], int] = {}
    for _ in range(4000):
        order, choices, logp = sample_sequential(AFF, rng)
        key = tuple(int(c) for c in choices)
        counts[key] = counts.get(key, 0) + 1
        if len(counts) <= 6:
            lp, _ = sequential_log_prob(torch.tensor(AFF[None]), torch.tensor(order[None]), torch.tensor(choices[None]))
            assert float(lp[0]) == pytest.approx(logp, abs=1e-9)
    assert len(counts) <= 6 and all(len(set(k)) == 3 for k in counts)  # never two robots on one cluster
    # marginalised over the uniform order, the frequency of the most likely matching matches enumeration
    p = np.mean([_prob_by_hand(AFF, list(o), [0, 1, 2]) for o in itertools.permutations(range(3))])
    assert counts[(0, 1, 2)] / 4000 == pytest.approx(p, abs=0.03)


def test_fewer_clusters_than_robots_share_only_when_all_taken_and_unreachable_robots_get_none() -> None:
    aff = np.array([[0.0, -np.inf], [1.0, 0.0], [0.0, 0.0], [-np.inf, -np.inf]])
    rng = np.random.default_rng(1)
    for _ in range(50):
        order, choices, logp = sample_sequential(aff, rng)
        assert choices[3] == -1 and choices[0] == 0
        assert set(choices[:3].tolist()) == {0, 1}  # both clusters used before any is shared
        lp, _ = sequential_log_prob(torch.tensor(aff[None]), torch.tensor(order[None]), torch.tensor(choices[None]))
        assert float(lp[0]) == pytest.approx(logp, abs=1e-9)
    assert hungarian_decode(aff).tolist() == [0, 0, 1, -1]  # 0 + 1 + 0: both clusters used, the best sum


def test_hungarian_maximises_the_summed_affinity() -> None:
    best = max(itertools.permutations(range(3)), key=lambda p: sum(AFF[i, p[i]] for i in range(3)))
    assert hungarian_decode(AFF).tolist() == list(best)
    wide = np.array([[1.0, 3.0, 2.0]])  # clusters outnumber robots: the rest stay unassigned
    assert hungarian_decode(wide).tolist() == [1]


def test_log_prob_ignores_padding() -> None:
    padded = np.full((1, 4, 5), -np.inf)
    padded[0, :3, :3] = AFF
    order, choices = [1, 2, 0], [2, 1, 0]
    plain, _ = sequential_log_prob(torch.tensor(AFF[None]), torch.tensor([order]), torch.tensor([choices]))
    pad, _ = sequential_log_prob(torch.tensor(padded), torch.tensor([order + [-1]]), torch.tensor([choices + [-1]]))
    assert float(pad[0]) == pytest.approx(float(plain[0]), abs=1e-9)


def test_assignment_score_sums_the_chosen_pairs() -> None:
    aff = torch.tensor([[[1.0, 2.0], [3.0, float("-inf")]]])
    cands = torch.tensor([[[0, 1], [1, 0], [1, -1]]])  # robot 1 has no cluster in the last one
    assert assignment_score(aff, cands).tolist() == [[1.0 + 0.0, 2.0 + 3.0, 2.0]]
