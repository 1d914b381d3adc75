"""A 400-node linear layer and 4-head attention, 64-d, one thread: milliseconds a call on the MKL path in force.

    MKL_CBWR=AUTO python docs/results/table005/mkl_compatible/attention_ms.py
    MKL_CBWR=COMPATIBLE python docs/results/table005/mkl_compatible/attention_ms.py
"""

import time

import torch

torch.set_num_threads(1)
x = torch.randn(1, 400, 64)
linear = torch.nn.Linear(64, 64)
attention = torch.nn.MultiheadAttention(64, 4, batch_first=True)
with torch.inference_mode():
    for _ in range(20):
        linear(x)
        attention(x, x, x, need_weights=False)
    start = time.perf_counter()
    for _ in range(500):
        linear(x)
        attention(x, x, x, need_weights=False)
    print(f"{(time.perf_counter() - start) / 500 * 1e3:.2f} ms")
