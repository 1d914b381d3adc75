"""The map predictor's training: the torch network against the NumPy one, the loss, the crops, the beliefs
collected, and a tiny run stopped and resumed."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
import torch

from mrexplore.config import EpisodesConfig, PredictorTrainConfig
from mrexplore.prediction.network import load_predictor
from mrexplore.prediction.unet import UNetNp
from mrexplore.training.predictor import (
    PREDICTOR_LOG_COLUMNS,
    BeliefJob,
    BeliefSet,
    _crops,
    collect_beliefs,
    free_scores,
    masked_bce,
    train_predictor,
)
from mrexplore.training.predictor_net import PredictorUNet
from mrexplore.types import MrExploreError

TINY = PredictorTrainConfig(
    episodes=EpisodesConfig(resolution_m=0.2, max_steps=120, robots_min=2, robots_max=2),
    missions=2, val_missions=1, moments=2, width=2, crop_cells=16, batch=2, epochs=3, steps_per_epoch=2,
)  # fmt: skip


@pytest.mark.parametrize("width", [1, 3, 8])  # 8: the shipped width, whose wide layers take the shifted products
def test_the_numpy_network_computes_what_the_torch_one_does(width: int) -> None:
    torch.manual_seed(width)
    net = PredictorUNet(width)
    x = torch.rand(1, 3, 12, 20)
    with torch.no_grad():
        want = net(x)[0].numpy()
    got = UNetNp(width, {k: v.numpy() for k, v in net.state_dict().items()})(x[0].numpy())
    np.testing.assert_allclose(got, want, atol=1e-5)


def test_the_loss_counts_only_the_masked_cells() -> None:
    z = torch.tensor([[2.0, -1.0, 7.0]])
    y = torch.tensor([[1.0, 0.0, 0.0]])
    m = torch.tensor([[True, True, False]])
    want = (np.log1p(np.exp(-2.0)) + np.log1p(np.exp(-1.0))) / 2  # -log sigmoid(2), -log(1 - sigmoid(-1))
    assert float(masked_bce(z, y, m)) == pytest.approx(want)
    assert float(masked_bce(z, y, torch.zeros_like(m))) == 0.0


def test_free_scores_pool_cells_right_intersection_and_union() -> None:
    pred = np.array([True, True, False, False])
    label = np.array([True, False, False, True])
    assert free_scores(pred, label).tolist() == [4, 2, 1, 3]


def test_a_crop_holds_a_counted_cell_and_pads_with_unknown() -> None:
    x = np.zeros((3, 4, 4), np.float16)
    x[0] = 1.0  # all free
    mask = np.zeros((4, 4), bool)
    mask[0, 0] = True
    data = BeliefSet([x], [np.ones((4, 4), bool)], [mask])
    cx, cy, cm = _crops(data, 5, 8, np.random.default_rng(0))
    assert cx.shape == (5, 3, 8, 8) and cy.shape == cm.shape == (5, 8, 8)
    assert (cm.sum(dim=(1, 2)) == 1).all()  # the one counted cell, somewhere in every crop
    # every cell is the belief's (free) or padding (unknown), never both or neither
    assert torch.equal(cx[:, 0] + cx[:, 2], torch.ones(5, 8, 8)) and (cx[:, 1] == 0).all()
    assert torch.equal(cy, cx[:, 0])  # the label is the belief's own, padding is not free


def test_collected_beliefs_count_unknown_cells_only() -> None:
    out = collect_beliefs(BeliefJob("generated:3", 2, 5, TINY, index=7))
    assert out["index"] == 7
    data: BeliefSet = out["set"]
    assert 1 <= len(data) <= TINY.moments
    for x, label, mask in zip(data.x, data.label, data.mask, strict=True):
        assert x.shape[1:] == label.shape == mask.shape and x.shape[1] % 4 == 0 and x.shape[2] % 4 == 0
        np.testing.assert_allclose(x.astype(np.float32).sum(axis=0), 1.0, atol=1e-3)
        assert mask.any() and (x[2][mask] > 0.5).all()  # most planning cells under a counted cell are unknown


def _log(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_a_run_stopped_by_its_budget_resumes_where_it_stopped(tmp_path: Path) -> None:
    out = tmp_path / "run"
    path, best = train_predictor(TINY, out, None, minutes=1e-6, workers=1, progress=False)
    rows = _log(out / "log.csv")
    assert len(rows) == 1 and list(rows[0]) == PREDICTOR_LOG_COLUMNS  # the budget let one epoch run
    assert best["epoch"] == 1 and load_predictor(path).net.width == 2
    with pytest.raises(MrExploreError, match="already holds a training run; pass --resume"):
        train_predictor(TINY, out, None, workers=1, progress=False)
    with pytest.raises(MrExploreError, match="was trained with another config"):
        train_predictor(TINY.__class__(**{**TINY.__dict__, "lr": 0.1}), out, None, resume=True, progress=False)
    beliefs = (out / "beliefs.npz").read_bytes()
    train_predictor(TINY, out, None, workers=1, resume=True, progress=False)
    assert [int(r["epoch"]) for r in _log(out / "log.csv")] == [1, 2, 3]
    assert (out / "beliefs.npz").read_bytes() == beliefs  # collected once
    assert (out / "curve.png").stat().st_size > 0
    with pytest.raises(MrExploreError, match=r"nothing to resume in .* \(no state.pt\)"):
        train_predictor(TINY, tmp_path / "other", None, resume=True, progress=False)


def test_beliefs_round_trip_reading_each_archive_member_once() -> None:
    """An archive member decompresses anew at every access: reading one per belief took minutes and 24 GB."""
    rng = np.random.default_rng(0)
    shapes = [(4, 8), (8, 4), (12, 12)]
    data = BeliefSet(
        [rng.random((3, h, w)).astype(np.float16) for h, w in shapes],
        [rng.random((h, w)) < 0.5 for h, w in shapes],
        [rng.random((h, w)) < 0.5 for h, w in shapes],
    )
    arrays = data.to_arrays("train")
    reads: dict[str, int] = {}

    class Archive(dict):
        def __getitem__(self, key: str) -> np.ndarray:
            reads[key] = reads.get(key, 0) + 1
            return super().__getitem__(key)

    back = BeliefSet.from_arrays(Archive(arrays), "train")
    assert set(reads.values()) == {1} and len(reads) == 4
    for a, b in zip(data.x + data.label + data.mask, back.x + back.label + back.mask, strict=True):
        assert np.array_equal(a, b)
