"""Progress of long work: a bar on a terminal, elsewhere (a pipe, a log file, CI) a plain line every few
seconds, so that nobody waits in silence; or nothing where switched off."""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

from tqdm import tqdm

from mrexplore.runtime.kernel_cache import compiled_this_run

__all__ = ["Progress", "LINE_EVERY_S"]

LINE_EVERY_S = 5.0
"""Seconds between two progress lines where the output is no terminal."""


def _duration(seconds: float) -> str:
    """``'42 s'``, ``'3 min 05 s'`` or ``'1 h 02 min'``.

    Examples
    --------
    >>> _duration(42.4), _duration(185), _duration(3720)
    ('42 s', '3 min 05 s', '1 h 02 min')
    """
    s = round(seconds)
    if s < 60:
        return f"{s} s"
    if s < 3600:
        return f"{s // 60} min {s % 60:02d} s"
    return f"{s // 3600} h {s % 3600 // 60:02d} min"


_PACE_LINES = 4
"""The time left is estimated from the pace over this many of the last lines (from the start before)."""


class Progress:
    """``total`` units of work named ``desc``.

    ``show``: True, a bar; False, nothing; None (the default), a bar on a terminal and otherwise a line
    every :data:`LINE_EVERY_S` seconds (``desc: n/total unit (p%), elapsed, about T left``), and one at
    :meth:`close` where any was printed. ``detail`` adds a note to each line (the step, the coverage).
    """

    def __init__(
        self,
        total: float,
        desc: str,
        unit: str,
        show: bool | None = None,
        initial: float = 0,
        leave: bool = True,
        stream: TextIO | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.total, self.desc, self.unit, self.n = total, desc, unit, initial
        tty = self.stream.isatty()
        self.mode = "bar" if show or (show is None and tty) else ("lines" if show is None else "off")
        self._bar = (
            tqdm(total=total, initial=initial, unit=unit, desc=desc, leave=leave, file=self.stream)
            if self.mode == "bar"
            else None
        )
        self._clock = clock
        self._start = clock()
        self._next_line = self._start + LINE_EVERY_S
        self._lines = 0
        self._said = initial
        self._first = initial
        self._seen: list[tuple[float, float]] = [(self._start, initial)]
        """(time, progress) at each line: the time left is estimated from the last few lines' pace, so that a
        slow start (a first run compiling its kernels) does not stretch every estimate after it."""
        self.detail = ""
        self.limit_s: float | None = None
        """A time budget (seconds from the start): the time left said is never beyond it."""

    def update(self, n: float = 1) -> None:
        self.set(self.n + n)

    def set(self, n: float) -> None:
        """Progress is ``n`` units now."""
        if self._bar is not None:
            self._bar.update(n - self.n)
        self.n = n
        if self.mode == "lines" and self._clock() >= self._next_line:
            self._line()

    def _line(self) -> None:
        now = self._clock()
        elapsed = now - self._start
        done = self.n - self._first
        pct = 100 * self.n / self.total if self.total else 100.0
        count = f"{pct:.0f}%" if self.unit == "%" else f"{self.n:g}/{self.total:g} {self.unit} ({pct:.0f}%)"
        text = f"{self.desc}: {count}, {_duration(elapsed)}"
        self._seen = [*self._seen[-(_PACE_LINES - 1) :], (now, self.n)]
        t0, paced = self._seen[0][0], self.n - self._seen[0][1]
        paced_enough = len(self._seen) >= _PACE_LINES and paced > 0
        if done > 0 and self.n < self.total and not paced_enough and compiled_this_run():
            text += ", no estimate while the kernels compile"  # the pace so far says nothing of the rest
        elif done > 0 and self.n < self.total:
            left = elapsed / done * (self.total - self.n)
            if paced_enough:
                left = (now - t0) / paced * (self.total - self.n)
            if self.limit_s is not None:
                left = max(0.0, min(left, self.limit_s - elapsed))
            text += f", about {_duration(left)} left"
        if self.detail:
            text += f", {self.detail}"
        print(text, file=self.stream, flush=True)
        self._lines += 1
        self._said = self.n
        self._next_line = now + LINE_EVERY_S

    def close(self) -> None:
        """End the bar; where lines were printed, a last one with the final count (unless the last said it)."""
        if self._bar is not None:
            bar = self._bar
            if bar.leave and not bar.disable and bar.last_print_n == bar.n:
                # tqdm's close() prints the last state again, a second line where output is no terminal
                bar.fp.write("\n")
                bar.fp.flush()
                bar.disable = True
            bar.close()
            self._bar = None
        elif self.mode == "lines" and self._lines and self.n != self._said:
            self._line()
        self.mode = "off"
