"""The one thread pool shared by the work that releases the GIL (beam casting, distance fields, the map
predictor run beside the rest of a decision).

Threads pay where one mission has the machine to itself. Where missions already run one per core (the
benchmark's worker processes), they only add hand-over costs, so the benchmark sets ``MREXPLORE_THREADS=1``
in its workers' environment and every map below runs inline.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from typing import TypeVar

from mrexplore.config.run import runtime_value

__all__ = ["THREADS_ENV", "thread_count", "map_threads", "start_thread"]

THREADS_ENV = "MREXPLORE_THREADS"
"""The environment variable of the ``runtime.threads`` setting, which worker processes are started with."""
_T = TypeVar("_T")
_R = TypeVar("_R")
_pool: ThreadPoolExecutor | None = None
_PREFIX = "mrexplore-pool"


def thread_count() -> int:
    """Threads to use: the ``runtime.threads`` setting (``$MREXPLORE_THREADS``) when set, else one per core."""
    n: int | None = runtime_value("threads")
    return n if n is not None else os.cpu_count() or 1


def map_threads(fn: Callable[[_T], _R], items: Sequence[_T]) -> list[_R]:
    """``[fn(x) for x in items]``, on the shared pool when more than one thread is allowed (inline when
    called from one of the pool's own threads: waiting there on the pool could leave no thread to run).

    Examples
    --------
    >>> map_threads(lambda x: x * x, [1, 2, 3])
    [1, 4, 9]
    """
    pool = _shared_pool()
    if pool is None or len(items) < 2:
        return [fn(x) for x in items]
    return list(pool.map(fn, items))


def start_thread(fn: Callable[[], _R]) -> Future[_R]:
    """``fn()`` started on the shared pool, to run beside the caller's own work, where more than one thread is
    allowed; run here and now otherwise (and when called from one of the pool's own threads). Its result or
    its exception comes from the future either way.

    Examples
    --------
    >>> start_thread(lambda: 6 * 7).result()
    42
    """
    pool = _shared_pool()
    if pool is not None:
        return pool.submit(fn)
    done: Future[_R] = Future()
    try:
        done.set_result(fn())
    except Exception as exc:  # noqa: BLE001 - handed to whoever reads the future, as the pool would
        done.set_exception(exc)
    return done


def _shared_pool() -> ThreadPoolExecutor | None:
    """The shared pool at the allowed size; None where one thread is allowed or the caller is a pool thread
    (waiting there on the pool could leave no thread to run)."""
    global _pool
    n = thread_count()
    if n <= 1 or threading.current_thread().name.startswith(_PREFIX):
        return None
    if _pool is None or _pool._max_workers != n:  # noqa: SLF001 - resize when the setting changed
        _pool = ThreadPoolExecutor(max_workers=n, thread_name_prefix=_PREFIX)
    return _pool
