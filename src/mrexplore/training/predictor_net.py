"""The map predictor's U-Net in torch, for training; :class:`~mrexplore.prediction.unet.UNetNp` runs the
same weights without torch."""

from __future__ import annotations

import torch
from torch import nn

from mrexplore.prediction.unet import DILATION, LAYERS, layer_shapes

__all__ = ["PredictorUNet"]


class PredictorUNet(nn.Module):
    """Three channels in, one logit (free) out per cell; two max-pooling levels, dilated convolutions (2, 4)
    at the coarsest, nearest-neighbour upsampling and skip connections."""

    enc1: nn.Conv2d
    enc2: nn.Conv2d
    mid1: nn.Conv2d
    mid2: nn.Conv2d
    mid3: nn.Conv2d
    dec2: nn.Conv2d
    dec1: nn.Conv2d
    head: nn.Conv2d

    def __init__(self, width: int = 8) -> None:
        super().__init__()
        self.width = width
        for name, (o, i, k) in layer_shapes(width).items():
            d = DILATION.get(name, 1)
            setattr(self, name, nn.Conv2d(i, o, k, padding=d * (k // 2), dilation=d))
        assert [n for n, _ in self.named_children()] == list(LAYERS)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """``(B, 3, h, w)`` -> ``(B, h, w)`` logits; ``h`` and ``w`` multiples of 4."""
        relu, pool = torch.relu, nn.functional.max_pool2d

        def up(t: torch.Tensor) -> torch.Tensor:
            return t.repeat_interleave(2, dim=2).repeat_interleave(2, dim=3)

        e1 = relu(self.enc1(x))
        e2 = relu(self.enc2(pool(e1, 2)))
        m = relu(self.mid1(pool(e2, 2)))
        m = relu(self.mid2(m))
        m = relu(self.mid3(m))
        d2 = relu(self.dec2(torch.cat([up(m), e2], dim=1)))
        d1 = relu(self.dec1(torch.cat([up(d2), e1], dim=1)))
        out: torch.Tensor = self.head(d1)[:, 0]
        return out
