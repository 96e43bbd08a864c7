"""A progress display for sweeps: designs done out of the total, elapsed time, time left."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, TextIO

__all__ = ["SweepProgress", "format_duration"]


def format_duration(seconds: float) -> str:
    """``M:SS`` or ``H:MM:SS``.

    Examples
    --------
    >>> format_duration(75.4), format_duration(3725)
    ('1:15', '1:02:05')
    """
    total = round(seconds)
    hours, rest = divmod(total, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


class SweepProgress:
    """Called as ``progress(done, total)``: a bar on a terminal, or one line per call.

    The time left is estimated from the designs finished since the first call
    (those found done in the table cost nothing).

    Parameters
    ----------
    stream : text stream
        Where to write (stderr).
    terminal : bool
        Redraw one line in place (``\\r``) rather than write a line per call.
    clock : callable, optional
        Seconds, monotonic (``time.monotonic``).
    width : int, default 30
        Characters of the bar.

    Examples
    --------
    >>> import io
    >>> ticks = iter([0.0, 10.0, 20.0])
    >>> out = io.StringIO()
    >>> progress = SweepProgress(out, terminal=False, clock=lambda: next(ticks), width=10)
    >>> progress(2, 10); progress(4, 10); progress(6, 10)
    >>> print(out.getvalue(), end="")
    sweep [##........]  2/10 designs, 0:00 elapsed
    sweep [####......]  4/10 designs, 0:10 elapsed, about 0:30 left
    sweep [######....]  6/10 designs, 0:20 elapsed, about 0:20 left
    """

    def __init__(
        self,
        stream: TextIO | Any,
        terminal: bool,
        clock: Callable[[], float] = time.monotonic,
        width: int = 30,
    ) -> None:
        self.stream = stream
        self.terminal = terminal
        self.clock = clock
        self.width = width
        self.start: float | None = None
        self.first_done = 0

    def line(self, done: int, total: int, elapsed: float) -> str:
        """The text shown for ``done`` designs out of ``total`` after ``elapsed`` seconds."""
        filled = self.width * done // total if total else self.width
        bar = "#" * filled + "." * (self.width - filled)
        digits = len(str(total))
        text = f"sweep [{bar}] {done:>{digits}}/{total} designs, {format_duration(elapsed)} elapsed"
        finished = done - self.first_done
        if 0 < finished and done < total:
            left = elapsed / finished * (total - done)
            text += f", about {format_duration(left)} left"
        return text

    def __call__(self, done: int, total: int) -> None:
        now = self.clock()
        if self.start is None:
            self.start, self.first_done = now, done
        text = self.line(done, total, now - self.start)
        if self.terminal:
            end = "\n" if done >= total else ""
            self.stream.write(f"\r{text}\x1b[K{end}")
        else:
            self.stream.write(text + "\n")
        self.stream.flush()
