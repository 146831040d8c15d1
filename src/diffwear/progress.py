"""A line now and then through a long wait, so that nothing looks hung.

`progress_line` says, while a block runs, how long it has run against an
estimate (a long compile's, `diffwear.mechanism_file.size`): one line
rewritten in place on a terminal, a line each time in a log file.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TextIO

# Seconds between the lines of `progress_line`.
PROGRESS_EVERY_SECONDS = 10.0


def minutes(seconds: float) -> str:
    """A wait in words: seconds below a minute and a half, minutes above."""
    return f"{seconds:.0f} s" if seconds < 90 else f"{seconds / 60:.0f} min"


@contextmanager
def progress_line(what: str, seconds: float, stream: TextIO | None = None,
                  every: float | None = None) -> Iterator[None]:
    """While the block runs, say every ``every`` seconds (default
    `PROGRESS_EVERY_SECONDS`) on ``stream`` (default stderr) how long ``what``
    has run against its estimate of ``seconds``: one line rewritten in place
    on a terminal, a line each time otherwise (a log file)."""
    out = sys.stderr if stream is None else stream
    every = PROGRESS_EVERY_SECONDS if every is None else every
    start = time.perf_counter()
    stop = threading.Event()
    try:
        tty = out.isatty()
    except (AttributeError, ValueError):
        tty = False
    said = []

    def tick() -> None:
        while not stop.wait(every):
            text = (f"diffwear: {what}: {time.perf_counter() - start:.0f} s so far, of an "
                    f"estimated {minutes(seconds)}")
            try:
                out.write(f"\r{text}" if tty else f"{text}\n")
                out.flush()
            except (OSError, ValueError):  # a closed stream: stop saying it
                return
            said.append(text)

    thread = threading.Thread(target=tick, name="diffwear-progress", daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        if tty and said:
            try:
                out.write("\n")
                out.flush()
            except (OSError, ValueError):
                pass


__all__ = ["PROGRESS_EVERY_SECONDS", "minutes", "progress_line"]
