"""The map predictor without torch: its convolution, its input, its prediction's frame and its file."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest
from conftest import state_grid

from mrexplore.prediction.encoding import belief_channels
from mrexplore.prediction.network import PREDICTOR_FORMAT, REACH_M, MapPredictor, load_predictor
from mrexplore.prediction.unet import UNetNp, _conv, _conv_up_and_skip, _Scratch, layer_shapes, phase_weights
from mrexplore.runtime.weights_archive import write_weights_archive
from mrexplore.types import CellState, MrExploreError


def _reference_conv(x: np.ndarray, w: np.ndarray, b: np.ndarray, dilation: int) -> np.ndarray:
    """Zero-padded same-size cross-correlation, one output at a time."""
    C, H, W = x.shape
    n_out, _, k, _ = w.shape
    p = dilation * (k // 2)
    xp = np.pad(x, ((0, 0), (p, p), (p, p)))
    out = np.zeros((n_out, H, W))
    for o in range(n_out):
        for r in range(H):
            for c in range(W):
                patch = xp[:, r : r + dilation * (k - 1) + 1 : dilation, c : c + dilation * (k - 1) + 1 : dilation]
                out[o, r, c] = (patch * w[o]).sum() + b[o]
    return out


@pytest.mark.parametrize("dilation", [1, 2, 4])
@pytest.mark.parametrize("channels", [3, 17])  # stacked copies below 16 input channels, shifted products above
def test_the_convolution_is_a_plain_cross_correlation_with_zero_padding(dilation: int, channels: int) -> None:
    rng = np.random.default_rng(dilation)
    x = rng.normal(size=(channels, 7, 9)).astype(np.float32)
    w = rng.normal(size=(2, channels, 3, 3)).astype(np.float32)
    b = rng.normal(size=2).astype(np.float32)
    np.testing.assert_allclose(_conv(x, w, b, dilation), _reference_conv(x, w, b, dilation), atol=1e-4)


@pytest.mark.parametrize(("coarse_ch", "skip_ch"), [(2, 1), (17, 3)])
def test_the_decoder_convolution_equals_one_over_the_upsampled_grid_stacked_on_the_skip(
    coarse_ch: int, skip_ch: int
) -> None:
    """Four 2 x 2 convolutions of the coarse grid, one per parity of row and column, give what the 3 x 3
    convolution gives on the grid upsampled by repeating each cell, borders included."""
    rng = np.random.default_rng(coarse_ch)
    coarse = rng.normal(size=(coarse_ch, 3, 5)).astype(np.float32)
    skip = rng.normal(size=(skip_ch, 6, 10)).astype(np.float32)
    w = rng.normal(size=(4, coarse_ch + skip_ch, 3, 3)).astype(np.float32)
    b = rng.normal(size=4).astype(np.float32)
    stacked = np.concatenate([coarse.repeat(2, axis=1).repeat(2, axis=2), skip])
    want = _reference_conv(stacked, w, b, 1)
    w_skip = np.ascontiguousarray(w[:, coarse_ch:])
    got = _conv_up_and_skip(coarse, skip, phase_weights(w[:, :coarse_ch]), w_skip, b, _Scratch(), "dec")
    np.testing.assert_allclose(got, want, atol=1e-4)


def test_the_phase_weights_of_a_tap_pattern_add_as_counted_by_hand() -> None:
    """One input and output channel, tap (i, j) weighing 10 ** (3 * i + j): phase (0, 0) reads coarse offsets
    -1 and 0 in both axes, its offset (0, 0) summing the four taps (1, 1), (1, 2), (2, 1), (2, 2)."""
    w = (10.0 ** np.arange(9)).reshape(1, 1, 3, 3).astype(np.float32)
    k = phase_weights(w).reshape(2, 2, 2, 2)  # phase row, phase column, coarse offset u, v
    assert k[0, 0, 0, 0] == 1  # tap (0, 0) alone reads offset (-1, -1)
    assert k[0, 0, 1, 1] == 1e4 + 1e5 + 1e7 + 1e8
    assert k[1, 1, 0, 0] == 1 + 10 + 1e3 + 1e4  # phase (1, 1), offset (0, 0): taps rows 0-1, columns 0-1
    assert k[1, 1, 1, 1] == 1e8  # tap (2, 2) alone reads offset (+1, +1)
    assert k.sum(axis=(2, 3)).tolist() == [[w.sum()] * 2] * 2  # every phase uses every tap once


def test_the_network_answers_alike_whatever_grids_it_ran_on_before() -> None:
    """The forward pass keeps its arrays between calls: a grid after a larger and a smaller one gets what a
    fresh network gives it, and an answer already given is not overwritten by the next call."""
    rng = np.random.default_rng(5)
    # width 8: the wide layers take the shifted products, whose padded arrays are reused too
    state = {k: rng.normal(scale=0.3, size=v.shape).astype(np.float32) for k, v in _zero_state(8).items()}
    x_small, x_large = (rng.random((3, h, w)).astype(np.float32) for h, w in ((8, 12), (16, 20)))
    fresh_small, fresh_large = UNetNp(8, state)(x_small), UNetNp(8, state)(x_large)
    net = UNetNp(8, state)
    first = net(x_large)
    np.testing.assert_array_equal(net(x_small), fresh_small)
    np.testing.assert_array_equal(net(x_large), fresh_large)
    np.testing.assert_array_equal(first, fresh_large)


def test_the_input_pools_states_into_shares_and_pads_with_unknown() -> None:
    state = state_grid(
        """
        .#?
        ..?
        """
    )
    x = belief_channels(state, 1)
    assert x.shape == (3, 4, 4)  # padded to a multiple of 4 (two pooling levels)
    assert x[:, 0, 0].tolist() == [1, 0, 0] and x[:, 0, 1].tolist() == [0, 1, 0] and x[:, 0, 2].tolist() == [0, 0, 1]
    assert (x[2, 2:, :] == 1).all() and (x[2, :, 3] == 1).all()


@pytest.mark.parametrize("factor", [1, 2, 3, 4])
def test_the_pooled_input_equals_the_shares_counted_block_by_block(factor: int) -> None:
    """The one-pass count against each block's share of each state, padding unknown, for grids that are no
    multiple of the block."""
    rng = np.random.default_rng(factor)
    for shape in [(1, 1), (5, 7), (13, 11), (16, 16)]:
        state = rng.choice(np.array([CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN], np.uint8), size=shape)
        x = belief_channels(state, factor)
        step = factor * 4
        Hp, Wp = -(-shape[0] // step) * step, -(-shape[1] // step) * step
        padded = np.full((Hp, Wp), CellState.UNKNOWN, np.uint8)
        padded[: shape[0], : shape[1]] = state
        assert x.shape == (3, Hp // factor, Wp // factor) and x.dtype == np.float32
        for k, s in enumerate((CellState.FREE, CellState.OCCUPIED, CellState.UNKNOWN)):
            for r in range(Hp // factor):
                for c in range(Wp // factor):
                    block = padded[r * factor : (r + 1) * factor, c * factor : (c + 1) * factor]
                    assert x[k, r, c] == np.float32((block == s).sum() / factor**2)


def _zero_state(width: int, head_bias: float = 0.0) -> dict[str, np.ndarray]:
    state = {}
    for name, (o, i, k) in layer_shapes(width).items():
        state[f"{name}.weight"] = np.zeros((o, i, k, k), np.float32)
        state[f"{name}.bias"] = np.zeros(o, np.float32)
    state["head.bias"][:] = head_bias
    return state


def test_known_cells_keep_their_state_and_far_unknown_cells_are_free() -> None:
    # logit -2 everywhere: p = 0.119 on unknown cells within reach of the known ones
    pred = MapPredictor(UNetNp(2, _zero_state(2, head_bias=-2.0)), 0.2, Path("x.npz"), "", {})
    state = np.full((4, 400), CellState.UNKNOWN, np.uint8)
    state[1, :3] = [CellState.FREE, CellState.OCCUPIED, CellState.FREE]
    p = pred.p_free(state, 0.1)
    assert p[1, :3].tolist() == [1.0, 0.0, 1.0]
    np.testing.assert_allclose(p[1, 3:40], 1 / (1 + np.exp(2.0)), rtol=1e-5)
    reach = round(REACH_M / 0.1)
    assert (p[:, 3 + reach + 8 :] == 1.0).all()  # beyond the box the network ran on (+ one pooling step)


def test_a_belief_with_nothing_known_is_predicted_free_everywhere() -> None:
    pred = MapPredictor(UNetNp(2, _zero_state(2, head_bias=-2.0)), 0.2, Path("x.npz"), "", {})
    p = pred.p_free(np.full((5, 6), CellState.UNKNOWN, np.uint8), 0.1)
    assert p.dtype == np.float32 and (p == 1.0).all()  # no known cell: no box the network runs on


def test_a_predictor_file_round_trips(tmp_path: Path) -> None:
    path = tmp_path / "p.npz"
    write_weights_archive(path, {"format": PREDICTOR_FORMAT, "width": 2, "cell_m": 0.2}, _zero_state(2, 1.0))
    loaded = load_predictor(path)
    assert loaded.cell_m == 0.2 and loaded.net.width == 2 and len(loaded.sha256) == 64
    assert loaded.describe() == {"path": str(path), "sha256": loaded.sha256}


def test_bad_predictor_files_get_one_line_each(tmp_path: Path) -> None:
    missing = tmp_path / "missing.npz"
    with pytest.raises(MrExploreError) as e:
        load_predictor(missing)
    assert str(e.value) == (
        f"predictor file {missing} not found; pass a file written by 'mrexplore train --target predictor' "
        "with --predictor"
    )
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip")
    with pytest.raises(MrExploreError, match=r"is not a mrexplore map predictor \(BadZipFile\); retrain it$"):
        load_predictor(junk)
    headless = tmp_path / "headless.npz"
    np.savez(headless, a=np.zeros(2))
    with pytest.raises(MrExploreError, match=r"is not a mrexplore map predictor \(no header\); retrain it$"):
        load_predictor(headless)
    policy = tmp_path / "policy.npz"
    write_weights_archive(policy, {"format": "mrexplore-policy-1"}, {"a": np.zeros(1)})
    with pytest.raises(MrExploreError, match=r"\(no predictor format tag\); retrain it$"):
        load_predictor(policy)
    narrow = tmp_path / "narrow.npz"
    write_weights_archive(narrow, {"format": PREDICTOR_FORMAT, "width": 3, "cell_m": 0.2}, _zero_state(2))
    with pytest.raises(MrExploreError, match=r"does not fit this network \(enc1 has shape .*\); retrain it$"):
        load_predictor(narrow)


def test_a_predictor_whose_weights_changed_after_saving_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "p.npz"
    write_weights_archive(path, {"format": PREDICTOR_FORMAT, "width": 2, "cell_m": 0.2}, _zero_state(2))
    with np.load(path) as z:
        members = {k: z[k] for k in z.files}
    members["w:head.bias"] = np.ones(1, np.float32)
    forged = tmp_path / "forged.npz"
    np.savez(forged, **members)
    assert zipfile.is_zipfile(forged)
    with pytest.raises(MrExploreError) as e:
        load_predictor(forged)
    assert str(e.value) == (
        f"predictor file {forged} is corrupted: its weights do not match the digest saved with them; retrain it"
    )
