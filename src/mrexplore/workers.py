"""Worker processes that never outlive the run that started them (the benchmark's and the trainer's).

A pool's workers are spawned (not forked: a parent that already ran a mission holds thread pools whose
locks a forked child would inherit in whatever state they were). Each worker watches its parent: if the
parent dies, even by SIGKILL, which gives it no chance to clean up, the worker exits within
:data:`PARENT_POLL_S`. A parent that stops on an exception or a signal it can catch terminates its
workers at once (:func:`stop_pool`).
"""

from __future__ import annotations

import multiprocessing
import os
import threading
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from typing import Any

__all__ = ["worker_pool", "stop_pool", "PARENT_POLL_S"]

PARENT_POLL_S = 0.5
"""How often a worker checks that its parent is alive, seconds."""


def _watch_parent(parent_pid: int) -> None:
    while True:
        time.sleep(PARENT_POLL_S)
        if os.getppid() != parent_pid:
            os._exit(1)  # the parent is gone: nobody will read this worker's results


def _start_worker(parent_pid: int, init: Callable[..., None] | None, args: tuple[Any, ...]) -> None:
    threading.Thread(target=_watch_parent, args=(parent_pid,), daemon=True, name="parent-watch").start()
    if init is not None:
        init(*args)


def worker_pool(
    workers: int, initializer: Callable[..., None] | None = None, initargs: tuple[Any, ...] = ()
) -> ProcessPoolExecutor:
    """A spawned process pool of ``workers`` whose workers exit when this process dies; ``initializer``
    runs in each worker after the watch starts."""
    return ProcessPoolExecutor(
        max_workers=workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_start_worker,
        initargs=(os.getpid(), initializer, initargs),
    )


def stop_pool(pool: ProcessPoolExecutor) -> None:
    """Cancel what has not started and terminate the workers now (their episodes in flight are lost;
    finished results were already kept by the caller)."""
    processes = list(getattr(pool, "_processes", {}).values())  # the executor has no public handle on them
    pool.shutdown(wait=False, cancel_futures=True)
    for p in processes:
        if p.is_alive():
            p.terminate()
    for p in processes:
        p.join(timeout=5)
