"""Progress of long loops: a bar on a terminal, a line every few seconds in a log.

A tqdm bar redraws itself with carriage returns, which a log file (a Slurm job, ``make demo >
log``, CI) shows as one unreadable line or not at all. :func:`bar` gives the bar when stderr is
a terminal and, otherwise, writes a plain, complete line every ``log_interval_s`` seconds and
one at the end, so a non-interactive run still shows that it moves and how fast.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable

from tqdm import tqdm

__all__ = ["bar"]

#: Seconds between two progress lines when stderr is not a terminal.
LOG_INTERVAL_S = 10.0


# One self-contained line per report: no bar characters, which a log shows as noise.
_LOG_FORMAT = "{desc}: {n_fmt}/{total_fmt} {unit} ({percentage:.0f} %), {elapsed} elapsed, {rate_fmt}"
_LOG_FORMAT_OPEN = "{desc}: {n_fmt} {unit}, {elapsed} elapsed, {rate_fmt}"  # total unknown


class _LogLines(tqdm):
    """tqdm that prints whole lines (no carriage returns), at most one per ``mininterval``."""

    def display(self, msg=None, pos=None):  # tqdm's hook for drawing the bar
        self.fp.write((msg or self.__str__()).strip() + "\n")
        self.fp.flush()
        return True

    def close(self):
        if not self.disable and self.n != self.last_print_n:
            self.display()  # the final count, once
        self.disable = True  # tqdm.close would redraw the bar with a carriage return
        super().close()


def bar(iterable: Iterable | None = None, *, total: int | None = None, desc: str, unit: str = "it",
        log_interval_s: float = LOG_INTERVAL_S, file=None) -> tqdm:
    """A progress bar over ``iterable`` (or a manual one with ``total``; call ``update``).

    Args:
      iterable: what to iterate over; None for a manual bar (``with bar(...) as b: b.update()``).
      total: number of steps, if ``iterable`` has no length.
      desc: what is progressing (shown first on the line), e.g. ``"plan RRTConnect"``.
      unit: unit of one step, e.g. ``"edge"``.
      log_interval_s: seconds between lines when ``file`` is not a terminal.
      file: stream to write to; stderr by default.

    Returns:
      A ``tqdm`` object (iterate over it, or call ``update``/``close``; it is a context manager).
    """
    fp = sys.stderr if file is None else file
    if total is None and hasattr(iterable, "__len__"):
        total = len(iterable)
    if fp.isatty():
        return tqdm(iterable, total=total, desc=desc, unit=unit, leave=False, file=fp)
    return _LogLines(iterable, total=total, desc=desc, unit=unit, file=fp, mininterval=log_interval_s,
                     maxinterval=log_interval_s, bar_format=_LOG_FORMAT if total else _LOG_FORMAT_OPEN)
