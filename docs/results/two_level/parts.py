"""Per robot, the parts of a near/far field with blocks twice as wide beyond a bound, against one whole
search on blocks of 3 (the first recorded call; run with PYTHONPATH at a checkout with two_level.patch).

    python parts.py p1_85.pkl
"""

import pickle
import sys
import time

import numpy as np

import mrexplore.paths.far_field as ff

with open(sys.argv[1], "rb") as fh:
    c = pickle.load(fh)[0]  # noqa: S301 - a recording perf/replay_far_fields.py made
h, w = c["shape"]
p = np.unpackbits(c["passable"])[: h * w].reshape(h, w).astype(bool)
g = ff.coarse_grid(p, c["factor"])
g2 = g.coarser()
f = g.factor
print(f"blocks of 3: {g.passable.sum()} passable; blocks of 6: {g2.passable.sum()}")
for bound_m in (20.0, 30.0):
    b = bound_m / 0.05 / f
    t = np.zeros(4)
    for _ in range(2):  # the first round compiles
        t[:] = 0
        for s in c["sources"]:
            seeds = ff._seeds(p, g, s, c["radius"])
            keys = (seeds.cells / f).astype(np.float32)
            t0 = time.perf_counter()
            coarse, _ = ff._searched(g, seeds.blocks, keys, b)
            t1 = time.perf_counter()
            blocks2, keys2 = ff._outer_seeds(coarse, g, b - 4, seeds.blocks, b)
            t2 = time.perf_counter()
            ff._searched(g2, blocks2, keys2)
            t3 = time.perf_counter()
            ff._searched(g, seeds.blocks, keys)
            t += [t1 - t0, t2 - t1, t3 - t2, time.perf_counter() - t3]
    ms = t * 1e3 / len(c["sources"])
    print(
        f"{bound_m:.0f} m: ms a robot: blocks of 3 to the bound {ms[0]:.2f}, seeds of the ring {ms[1]:.2f}, "
        f"blocks of 6 beyond {ms[2]:.2f}; one whole search on blocks of 3 {ms[3]:.2f}"
    )
