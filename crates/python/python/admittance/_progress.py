"""Progress on long work (issue 33 part 6): a one-line bar or spinner on stderr, drawn only
when stderr is a terminal, ``CI`` is not set and the caller did not ask for quiet
(``set_quiet``, the commands' ``--quiet``). Elsewhere (CI, logs, pipes, tests) every
function here draws nothing and costs nothing: ``steps`` hands back its iterable as it is.

No dependency: a bar redrawn at most ten times a second with ``\\r``, cleared when done."""

from __future__ import annotations

import os
import sys
import threading
import time

_quiet = False

#: Seconds between redraws.
REDRAW = 0.1


def set_quiet(quiet: bool = True) -> None:
    """No progress from now on in this process (``--quiet``)."""
    global _quiet
    _quiet = bool(quiet)


def enabled() -> bool:
    """Whether progress is drawn: stderr is a terminal, ``CI`` is unset, not quiet."""
    if _quiet or os.environ.get("CI"):
        return False
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def _columns() -> int:
    """The terminal's width (80 when it does not say)."""
    try:
        cols = os.get_terminal_size(sys.stderr.fileno()).columns
    except (OSError, ValueError):
        cols = 0
    return cols if cols > 10 else 80


def _clock(seconds: float) -> str:
    s = int(seconds)
    return f"{s // 60}:{s % 60:02d}"


class Bar:
    """``label [=====>    ] 42% 0:31 (eta 0:43)`` for ``total`` units, or a spinner with the
    elapsed time when ``total`` is ``None``. Draws nothing unless ``enabled()`` at creation.
    A context manager; ``close`` clears the line."""

    def __init__(self, label: str, total: int | None = None, width: int = 30):
        self.label, self.total, self.width = label, total, width
        self.done = 0
        self.on = enabled()
        self.started = time.monotonic()
        self._last = 0.0
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._ticker = None
        if self.on:
            # Native code or a long job may hold off the next update: a thread redraws the
            # line (the clock, the spinner) meanwhile.
            self._ticker = threading.Thread(target=self._tick, daemon=True)
            self._ticker.start()

    def _tick(self):
        while not self._stop.wait(REDRAW * 2):
            self._draw()

    def _line(self) -> str:
        elapsed = time.monotonic() - self.started
        if self.total is None:
            spin = "|/-\\"[int(elapsed / (REDRAW * 2)) % 4]
            return f"{spin} {self.label} ({_clock(elapsed)})"
        total = max(self.total, 1)
        frac = min(self.done / total, 1.0)
        fill = int(frac * self.width)
        bar = "=" * fill + (">" if fill < self.width else "") + " " * max(self.width - fill - 1, 0)
        eta = f" (eta {_clock(elapsed * (1 - frac) / frac)})" if 0 < frac < 1 else ""
        return f"{self.label} [{bar}] {100 * frac:3.0f}% {_clock(elapsed)}{eta}"

    def _draw(self):
        with self._lock:
            if not self.on:
                return
            cols = _columns()
            sys.stderr.write("\r" + self._line()[: cols - 1].ljust(cols - 1))
            sys.stderr.flush()

    def update(self, n: int = 1) -> None:
        """``n`` more units done; redraws at most every ``REDRAW`` s."""
        self.done += n
        if self.on:
            now = time.monotonic()
            if now - self._last >= REDRAW:
                self._last = now
                self._draw()

    def set_label(self, label: str) -> None:
        self.label = label
        if self.on:
            self._draw()

    def close(self) -> None:
        """Clears the line (nothing when not drawn)."""
        if not self.on:
            return
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join()
        with self._lock:
            cols = _columns()
            sys.stderr.write("\r" + " " * (cols - 1) + "\r")
            sys.stderr.flush()
        self.on = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def steps(iterable, label: str, total: int | None = None):
    """``iterable`` with a bar of ``label`` advanced per item (``total``: ``len(iterable)``
    when it has one); the iterable itself, untouched, when progress is off."""
    if not enabled():
        return iterable
    if total is None:
        try:
            total = len(iterable)
        except TypeError:
            total = None
    return _stepping(iterable, label, total)


def _stepping(iterable, label, total):
    with Bar(label, total) as bar:
        for item in iterable:
            yield item
            bar.update()


def spinner(label: str) -> Bar:
    """A spinner with the elapsed time for one long call (``with spinner("training"): ...``)."""
    return Bar(label, None)


def log_line(text: str) -> None:
    """A message line that does not collide with a bar being drawn (bars redraw after it)."""
    if enabled():
        sys.stderr.write("\r\x1b[K")
    print(text, file=sys.stderr, flush=True)
