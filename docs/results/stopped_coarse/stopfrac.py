"""How far coarse searches stopped at their read blocks get, against whole ones, on recorded calls.

Needs the patched checkout of README.md (its ``far_fields(..., read_rc=)`` and ``_stop_blocks``) and
recordings made with it (they keep where each decision reads the fields).
"""

import pickle
import sys
import time

import numpy as np

from mrexplore.paths import far_field as ff

for rec in sys.argv[1:]:
    with open(rec, "rb") as f:
        calls = pickle.load(f)  # noqa: S301 - a recording of your own
    fr, stopped, tsb = [], 0, []
    for c in calls:
        h, w = c["shape"]
        passable = np.unpackbits(c["passable"])[: h * w].reshape(h, w).astype(bool)
        g = ff.coarse_grid(passable, c["factor"])
        t = time.perf_counter()
        ff._stop_blocks(g, np.vstack([c["read"], c["must"]]))
        tsb.append(1e3 * (time.perf_counter() - t))
        whole = ff.far_fields(passable, c["sources"], c["radius"], c["factor"], c["must"], c["own"], g)
        stop = ff.far_fields(passable, c["sources"], c["radius"], c["factor"], c["must"], c["own"], g, c["read"])
        for a, b in zip(whole, stop, strict=True):
            fa, fb = np.isfinite(a.coarse).sum(), np.isfinite(b.coarse).sum()
            fr.append(fb / max(fa, 1))
            stopped += b.bound < np.inf
    fr = np.array(fr)
    print(
        f"{rec}: fields {len(fr)}, stopped {stopped}, blocks settled mean {fr.mean():.2f} median "
        f"{np.median(fr):.2f}; finding the blocks to stop at {np.median(tsb):.1f} ms"
    )
