"""The experiments' link to the benchmark harness (`benchmarks/harness.py`,
importable as ``harness`` once this module is imported): its timing
(`harness.time_jitted`) and `write_record`, an experiment's results with the
provenance the harness records (`harness.metadata`: date, commit, versions,
device, CPU count, load)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1]
if str(BENCHMARKS) not in sys.path:
    sys.path.insert(0, str(BENCHMARKS))


def write_record(path: str | Path, **results) -> None:
    """``{"meta": provenance, **results}`` as JSON at ``path``."""
    from harness import metadata

    meta = {k: v for k, v in metadata(quick=False).items() if k != "quick"}  # no repeats here
    Path(path).write_text(json.dumps({"meta": meta, **results}, indent=1))
