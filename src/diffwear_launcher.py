"""The ``diffwear`` console command's first frame.

Importing `diffwear` loads JAX and XLA (about two seconds).  A Ctrl-C in
that time would end in a traceback from inside the import, where
`diffwear.cli.entry` cannot catch it: the console script imports the
package before it calls anything.  This module, outside the package, sets a
SIGINT handler that ends the process at once with exit 130 and the
command's one line, then imports the command and hands over to it (whose
own handler takes over from there).
"""

from __future__ import annotations

import os
import signal
import sys

__all__ = ["entry"]

MESSAGE = "diffwear: interrupted; no results were written\n"


def _end_while_starting(signum, frame):  # nothing written yet: nothing to keep
    sys.stderr.write(MESSAGE)
    sys.stderr.flush()
    os._exit(130)


def entry() -> None:
    """Import the command with Ctrl-C ending the process cleanly, then run it."""
    previous = signal.getsignal(signal.SIGINT)
    if previous is not signal.SIG_IGN:  # a process started immune (nohup, `&`) stays so
        signal.signal(signal.SIGINT, _end_while_starting)
    try:
        from diffwear.cli import command
    finally:
        signal.signal(signal.SIGINT, previous)
    command.entry()
