"""The shared thread pool: inline when one thread is allowed, the setting validated, calls started beside the caller."""

from __future__ import annotations

import threading

import pytest

from mrexplore.runtime.threads import THREADS_ENV, map_threads, start_thread, thread_count
from mrexplore.types import MrExploreError


def test_one_thread_runs_inline(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(THREADS_ENV, "1")
    assert map_threads(lambda _: threading.current_thread().name, [0, 1, 2]) == ["MainThread"] * 3


def test_several_threads_keep_order(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(THREADS_ENV, "3")
    assert thread_count() == 3
    assert map_threads(lambda x: 10 * x, list(range(7))) == [0, 10, 20, 30, 40, 50, 60]


@pytest.mark.parametrize("text", ["0", "two"])
def test_bad_setting_refused(monkeypatch: pytest.MonkeyPatch, text: str) -> None:
    monkeypatch.setenv(THREADS_ENV, text)
    with pytest.raises(
        MrExploreError, match=rf"^MREXPLORE_THREADS must be an integer >= 1, got '{text}'; unset it for the default$"
    ):
        thread_count()


@pytest.mark.parametrize(("threads", "inline"), [("1", True), ("2", False)])
def test_a_started_call_runs_beside_the_caller_or_inline(
    monkeypatch: pytest.MonkeyPatch, threads: str, inline: bool
) -> None:
    monkeypatch.setenv(THREADS_ENV, threads)
    future = start_thread(lambda: threading.current_thread().name)
    assert (future.result() == "MainThread") is inline

    def fails() -> None:
        raise ValueError("bad map")

    with pytest.raises(ValueError, match="^bad map$"):  # the exception comes from the future either way
        start_thread(fails).result()
