"""Write an experiment's record: its results with the provenance needed to
compare runs (date, commit, versions, device, CPU count, load)."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def write_record(path: str | Path, **results) -> None:
    """``{"meta": provenance, **results}`` as JSON at ``path``."""
    import jax

    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                            capture_output=True, text=True).stdout.strip()
    meta = {"date": time.strftime("%Y-%m-%d"), "commit": commit, "jax": jax.__version__,
            "python": platform.python_version(), "device": str(jax.devices()[0]),
            "cpu_count": os.cpu_count(), "load_average_1min": os.getloadavg()[0]}
    Path(path).write_text(json.dumps({"meta": meta, **results}, indent=1))
