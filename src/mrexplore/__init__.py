"""mrexplore: hierarchical multi-robot exploration (frontier preprocessing, global assignment, local routing)."""

import os

# Intel MKL, which does torch's matrix products on x86, picks its code path by the CPU, and the paths round
# differently: a learned planner's near-ties then break otherwise on another machine, and whole missions part
# (59 learned episodes of the 0.05 m table's 2,184 on an AVX-512 machine against the rows of an earlier one;
# all 59 the same again on this one path). MKL's compatible path (SSE2) runs on every x86 CPU, Intel's or not,
# so learned results repeat across machines. MKL reads this once, at its first matrix product, so it is
# set here, before this package ever uses torch; a value already set is kept (``MKL_CBWR=AUTO``: the CPU's
# fastest path, results tied to the CPU).
os.environ.setdefault("MKL_CBWR", "COMPATIBLE")

__version__ = "0.1.0"
