"""The ``diffwear`` command and its drivers: each module turns one command's
options into calls of the library and writes the output folder (report,
CSV, figures, ``summary.json``).

* `command`: the argument parser and the dispatch (exit codes 0 / 2 / 3 / 130);
* `run`: ``diffwear run FILE`` (a mechanism file: motion, contact, wear);
* `sweep`: ``diffwear sweep FILE`` (a sweep file over a ready-made model);
* `design`: ``diffwear design`` (the Ch. 8 bushing design);
* `calibrate`: ``diffwear calibrate DATASET`` (fit, residual, effects);
* `life`: ``diffwear life two-joint`` (the lives of one Ch. 8 design).

Only this package chooses the matplotlib backend; nothing below it imports it.
"""

from .command import build_parser, entry, main

__all__ = ["build_parser", "entry", "main"]
