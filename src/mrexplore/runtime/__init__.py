"""Runtime services shared by every layer: the thread pool, worker processes, progress lines, timing and
memory probes, numba's kernel cache, append-only CSV files, weight archives and where the example maps are."""
