"""The processes of one ``mrexplore ros2 launch``, started, killed, started again and ended together."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path
from typing import IO, Any

__all__ = ["TeamProcesses"]

_GRACE_S = 10.0
"""A process asked to end (SIGTERM) is killed after this long."""


def _die_with_parent() -> None:  # pragma: no cover - runs in the child, before exec
    """The child gets SIGTERM when the launcher dies, however it dies (Linux; elsewhere nothing)."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
    except OSError:
        pass


class TeamProcesses:
    """The processes of one launch by name, each with its command and log, started, killed, started again and
    ended together. Used from one thread: each child gets SIGTERM when the thread that started it ends."""

    def __init__(self, work: Path) -> None:
        self.work = work
        self.commands: dict[str, list[str]] = {}
        self.processes: dict[str, subprocess.Popen[str]] = {}
        self._logs: list[IO[str]] = []

    def start(self, name: str, cmd: list[str] | None = None, stdout: Any = subprocess.DEVNULL) -> subprocess.Popen[str]:
        """Start ``cmd`` (default: the command ``name`` ran before) with its stderr in ``name``.log."""
        cmd = cmd or self.commands[name]
        log = open(self.work / f"{name}.log", "a")  # noqa: SIM115 - closed in stop_all
        self._logs.append(log)
        self.commands[name] = cmd
        self.processes[name] = p = subprocess.Popen(
            cmd, stdout=stdout, stderr=log, text=True, preexec_fn=_die_with_parent
        )
        return p

    def kill(self, name: str) -> None:
        """End ``name`` at once, as a crash or a power cut would (SIGKILL)."""
        p = self.processes[name]
        if p.poll() is None:
            p.kill()
            p.wait()

    def stop_all(self) -> None:
        """End every process still running: SIGTERM, then SIGKILL after a grace period."""
        running = [p for p in self.processes.values() if p.poll() is None]
        for p in running:
            p.send_signal(signal.SIGTERM)
        t0 = time.monotonic()
        for p in running:
            try:
                p.wait(timeout=max(0.1, _GRACE_S - (time.monotonic() - t0)))
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()
        for log in self._logs:
            log.close()
        self._logs.clear()
