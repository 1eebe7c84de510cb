"""A progress line for long commands: done / total, rate and ETA on stderr (rewritten in place on a terminal, one
line every few seconds in logs)."""

from __future__ import annotations

import sys
import time


class Progress:
    """``Progress(total, "episodes")``; call :meth:`update` with the count done so far; :meth:`close` at the end."""

    def __init__(self, total: int, unit: str, label: str = "", stream=None) -> None:
        self.total, self.unit, self.label = total, unit, label
        self.stream = stream or sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.start = self.last = time.time()
        self.done = 0

    def update(self, done: int) -> None:
        self.done = done
        now = time.time()
        if now - self.last < (0.5 if self.tty else 10.0) and done < self.total:
            return
        self.last = now
        rate = done / max(now - self.start, 1e-9)
        eta = (self.total - done) / rate if rate > 0 else float("inf")
        line = (f"{self.label}{done}/{self.total} {self.unit} | {now - self.start:6.1f} s elapsed | "
                f"ETA {eta:6.1f} s")
        print(line.ljust(80), end="\r" if self.tty else "\n", file=self.stream, flush=True)

    def close(self) -> None:
        if self.tty:
            print(file=self.stream, flush=True)
