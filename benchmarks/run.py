#!/usr/bin/env python3
"""diffwear performance benchmarks.

    python benchmarks/run.py [--quick] [--json PATH] [--case NAME ...]

Each registered case (`CASES`: name -> function(repeats) -> metrics; one
module per case family in ``benchmarks/cases/``) builds its problem, times
the first call of its jitted function (compile + run) and ``repeats`` steady
calls, and returns a flat dict of metrics.  The table goes to stdout as
markdown, the full results (with machine and version metadata) to JSON, by
default ``benchmarks/results/latest.json`` (gitignored).  Timing, the table
and the JSON writer are in ``benchmarks/harness.py``.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parent
if str(BENCHMARKS) not in sys.path:  # the harness and the cases, beside this script
    sys.path.append(str(BENCHMARKS))

import harness  # noqa: E402
from cases import CASES  # noqa: E402
from cases.peers import EXUDYN_STEP, exudyn_peer, exudyn_python  # noqa: E402
from harness import (  # noqa: E402
    DEFAULT_JSON,
    QUICK_REPEATS,
    REPEATS,
    markdown,
    metadata,
    time_jitted,
    timed,
    write_results,
)

__all__ = ["CASES", "DEFAULT_JSON", "EXUDYN_STEP", "QUICK_REPEATS", "REPEATS", "exudyn_peer",
           "exudyn_python", "main", "markdown", "metadata", "run_cases", "time_jitted", "timed"]


def run_cases(names: Sequence[str] | None = None, *, quick: bool = False, log=print) -> dict:
    """Run the named cases (default: all) -> {"meta": ..., "cases": {name: metrics}}."""
    return harness.run_cases(CASES, names, quick=quick, log=log)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help=f"{QUICK_REPEATS} repeats instead of {REPEATS}")
    parser.add_argument("--json", type=Path, default=DEFAULT_JSON,
                        help="where to write the results (default: %(default)s)")
    parser.add_argument("--case", action="append", choices=list(CASES), metavar="NAME",
                        help="run only this case (repeatable); default: all of "
                             + ", ".join(repr(c) for c in CASES))
    args = parser.parse_args(argv)
    results = run_cases(args.case, quick=args.quick)
    print(markdown(results))
    write_results(results, args.json)
    print(f"\nwrote {args.json}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
