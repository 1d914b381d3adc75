"""Where the benchmark's episodes and the trainer's run: inline, in local worker processes that never
outlive the run that started them, or as Ray tasks (:class:`JobRunner`, the one start-up both use).

A pool's workers are spawned (not forked: a parent that already ran a mission holds thread pools whose
locks a forked child would inherit in whatever state they were). Each worker watches its parent: if the
parent dies, even by SIGKILL, which gives it no chance to clean up, the worker exits within
:data:`PARENT_POLL_S`. A parent that stops on an exception or a signal it can catch terminates its
workers at once (:func:`stop_pool`).
"""

from __future__ import annotations

import math
import multiprocessing
import os
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from typing import Any, Generic, Self, TypeVar

from mrexplore.types import MrExploreError

__all__ = ["JobRunner", "worker_pool", "stop_pool", "PARENT_POLL_S"]

J = TypeVar("J")
R = TypeVar("R")

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


class JobRunner(Generic[J, R]):
    """Runs ``fn`` over jobs, as a context manager: inline where ``workers`` is 1, in ``workers`` spawned
    local processes otherwise (0: one per core), or as Ray tasks of one CPU each where ``ray_address`` is
    given (``local`` starts Ray on this machine; ``auto`` or ``HOST:PORT`` joins a cluster). Leaving the
    context on an exception stops the workers at once (what finished was already handed back).

    ``init(*init_args)`` runs in each local worker; ``ray_env`` holds the environment variables of the Ray
    tasks.
    """

    def __init__(
        self,
        fn: Callable[[J], R],
        workers: int = 0,
        ray_address: str | None = None,
        init: Callable[..., None] | None = None,
        init_args: tuple[Any, ...] = (),
        ray_env: dict[str, str] | None = None,
    ) -> None:
        self.fn = fn
        self.workers = workers or os.cpu_count() or 1
        self.ray_address = ray_address
        self._init, self._init_args, self._ray_env = init, init_args, ray_env or {}
        self._pool: ProcessPoolExecutor | None = None
        self._remote: Any = None
        self._ray_started = False

    def __enter__(self) -> Self:
        if self.ray_address is not None:
            try:
                import ray
            except ImportError:
                raise MrExploreError("--ray-address needs Ray; install it with: pip install 'mrexplore[ray]'") from None
            if not ray.is_initialized():
                kwargs: dict[str, Any] = (
                    {"num_cpus": self.workers} if self.ray_address == "local" else {"address": self.ray_address}
                )
                ray.init(include_dashboard=False, log_to_driver=False, **kwargs)
                self._ray_started = True
            self._remote = ray.remote(num_cpus=1, runtime_env={"env_vars": self._ray_env})(self.fn)
        elif self.workers > 1:
            self._pool = worker_pool(self.workers, self._init, self._init_args)
        return self

    def __exit__(self, exc_type: type[BaseException] | None, *exc: object) -> None:
        if self._pool is not None:
            if exc_type is None:
                self._pool.shutdown(cancel_futures=True)
            else:
                stop_pool(self._pool)  # a kill, an interrupt or a failed job: no worker runs on
        if self._ray_started:
            import ray

            ray.shutdown()

    def run(self, jobs: Sequence[J], deadline: float = math.inf) -> Iterator[R]:
        """Results of ``jobs`` as they finish; jobs not started by ``deadline`` (``time.perf_counter``) are
        dropped (those running then finish)."""
        if self._remote is not None:
            import ray

            pending = [self._remote.remote(j) for j in jobs]
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                yield ray.get(done[0])
                if time.perf_counter() > deadline:
                    for ref in pending:
                        ray.cancel(ref)
                    return
        elif self._pool is not None:
            futures: set[Future[R]] = {self._pool.submit(self.fn, j) for j in jobs}
            while futures:
                done_f, futures = wait(futures, return_when=FIRST_COMPLETED)
                for f in done_f:
                    yield f.result()
                if time.perf_counter() > deadline:
                    for f in futures:
                        f.cancel()
                    futures = {f for f in futures if f.running()}
                    deadline = math.inf  # let the running ones finish, start no more
        else:
            for j in jobs:
                if time.perf_counter() > deadline:
                    return
                yield self.fn(j)
