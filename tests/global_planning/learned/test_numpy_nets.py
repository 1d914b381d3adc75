"""The NumPy forward passes against the torch modules they mirror: the same outputs (to float32 rounding)
on random weights and decisions, the same decisions from the shipped policies, and every learned strategy
running where torch cannot be imported."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import torch
from random_problems import random_problem as _random_problem

from mrexplore.cli.common import TORCH_MISSING
from mrexplore.config import LearnedConfig
from mrexplore.global_planning.learned.features import graph_inputs
from mrexplore.global_planning.learned.ncm_inputs import NcmConfig, ncm_inputs
from mrexplore.global_planning.learned.ncm_planner import NcmPlanner
from mrexplore.global_planning.learned.numpy_nets import GraphNetNp, NcmNetNp
from mrexplore.global_planning.learned.policy import LearnedPlanner
from mrexplore.global_planning.learned.policy_file import load_ncm_policy_np, load_policy_np
from mrexplore.training.checkpoint import VALUE_INPUTS, load_ncm_policy, load_policy
from mrexplore.training.hier_net import MultiGraphNet, collate
from mrexplore.training.ncm_net import NcmNet, ncm_collate


def _numpy_state(net: torch.nn.Module) -> dict[str, np.ndarray]:
    return {k: v.detach().numpy().copy() for k, v in net.state_dict().items()}


def _trained_like(seed: int) -> MultiGraphNet:
    """An mGNN whose every layer, the scoring MLP's last included, holds random weights."""
    torch.manual_seed(seed)
    net = MultiGraphNet(LearnedConfig(hidden=16, blocks=2), VALUE_INPUTS).eval()
    with torch.no_grad():
        torch.nn.init.normal_(net.score[-1].weight, std=0.5)
        net.set_edge_weights([-1.0, 0.5, -0.3, 0.2, 0.1])
    return net


def test_the_mgnn_residual_equals_torch_on_random_decisions() -> None:
    net = _trained_like(1)
    mirror = GraphNetNp(net.cfg, _numpy_state(net))
    assert not mirror.scores_nothing()
    rng = np.random.default_rng(5)
    for _ in range(100):
        g = graph_inputs(_random_problem(rng), net.cfg, LearnedPlanner(net).heuristic)
        with torch.no_grad():
            batch = collate([g])
            want = net.residual(*net.encode(batch), batch)[0, : g.n_robots, : g.n_clusters].numpy()
        np.testing.assert_allclose(mirror.residual(g), want, rtol=1e-4, atol=1e-5)


@pytest.mark.parametrize("path", [False, True])
def test_a_network_that_reads_the_predicted_gain_equals_torch(path: bool) -> None:
    torch.manual_seed(3)
    cfg = LearnedConfig(hidden=16, blocks=1, use_predicted_gain=True, use_predicted_path=path)
    net = MultiGraphNet(cfg, VALUE_INPUTS).eval()
    weights = [-1.0, 0.5, -0.3, 0.2, 0.1, 0.7] + [0.4] * path
    with torch.no_grad():
        torch.nn.init.normal_(net.score[-1].weight, std=0.5)
        net.set_edge_weights(weights)
    mirror = GraphNetNp(net.cfg, _numpy_state(net))
    assert mirror.edge_weights.tolist() == pytest.approx(weights)
    rng = np.random.default_rng(7)
    for _ in range(20):
        p = _random_problem(rng)
        shortcut = rng.uniform(0, 20, (p.n_robots, p.n_clusters)) if path else None
        g = graph_inputs(p, net.cfg, LearnedPlanner(net).heuristic, rng.uniform(0, 30, p.n_clusters), shortcut)
        with torch.no_grad():
            batch = collate([g])
            want = net.residual(*net.encode(batch), batch)[0, : g.n_robots, : g.n_clusters].numpy()
        np.testing.assert_allclose(mirror.residual(g), want, rtol=1e-4, atol=1e-5)


def test_ncm_logits_equal_torch_on_random_decisions() -> None:
    torch.manual_seed(2)
    net = NcmNet(NcmConfig(hidden=16, heads=4, blocks=2)).eval()
    mirror = NcmNetNp(net.cfg, _numpy_state(net))
    rng = np.random.default_rng(6)
    for _ in range(100):
        x = ncm_inputs(_random_problem(rng))
        with torch.no_grad():
            want = net(ncm_collate([x]))[0].numpy()
        got = mirror.logits(x)
        assert np.array_equal(np.isfinite(got), np.isfinite(want))
        np.testing.assert_allclose(got[np.isfinite(got)], want[np.isfinite(want)], rtol=1e-4, atol=1e-4)


def test_the_shipped_policies_decide_alike_in_numpy_and_torch() -> None:
    hier_np, hier_t = LearnedPlanner(load_policy_np().net), LearnedPlanner(load_policy().net)
    ncm_np, ncm_t = NcmPlanner(load_ncm_policy_np().net), NcmPlanner(load_ncm_policy().net)
    rng = np.random.default_rng(7)
    for _ in range(200):
        p = _random_problem(rng)
        assert hier_np.assign(p).cluster_of_robot.tolist() == hier_t.assign(p).cluster_of_robot.tolist()
        assert ncm_np.assign(p).cluster_of_robot.tolist() == ncm_t.assign(p).cluster_of_robot.tolist()


def test_missing_or_extra_weights_are_named() -> None:
    state = _numpy_state(_trained_like(0))
    del state["score.2.bias"]
    with pytest.raises(ValueError, match=r"^missing weights score\.2\.bias$"):
        GraphNetNp(LearnedConfig(hidden=16, blocks=2), state)
    state = _numpy_state(NcmNet())
    state["stray.weight"] = np.zeros(1, np.float32)
    with pytest.raises(ValueError, match=r"^unexpected weights stray\.weight$"):
        NcmNetNp(NcmConfig(), state)


NO_TORCH = """
import importlib.abc, json, sys
class Refuse(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name == "torch" or name.startswith("torch."):
            raise ImportError("no torch here")
sys.meta_path.insert(0, Refuse())
from mrexplore.cli import main
rows = []
for s in ("hier", "ncm", "ncm-sampled"):
    code = main(["explore", "--map", "generated:3", "--robots", "2", "--resolution", "0.2", "--strategy", s,
                 "--json", "--no-progress"])
    assert code == 0, s
print("torch" in sys.modules)
print(main(["train", "--out", sys.argv[1], "--minutes", "1"]))
"""


@pytest.mark.slow
def test_every_learned_strategy_runs_where_torch_cannot_be_imported(tmp_path) -> None:
    """Without torch every strategy explores, torch is never imported, and training says what to install."""
    out = subprocess.run(
        [sys.executable, "-c", NO_TORCH, str(tmp_path / "run")],
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert out.returncode == 0, out.stderr[-2000:]
    lines = out.stdout.strip().splitlines()
    records = [json.loads(line) for line in lines[:-2]]
    assert [r["strategy"] for r in records] == ["hier", "ncm", "ncm-sampled"]
    assert all(r["coverage"] >= 0.99 for r in records) and lines[-2:] == ["False", "2"]
    assert out.stderr.strip().splitlines()[-1] == f"mrexplore: error: {TORCH_MISSING}"
