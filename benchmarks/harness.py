"""The benchmark harness shared by `run.py`, its cases (`cases/`) and the
experiments: timing of jitted calls (first call and the median of steady
calls), the run's provenance (`metadata`), running registered cases, the
markdown table and the JSON results file."""

from __future__ import annotations

import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT / "src") not in sys.path:  # benchmark this checkout, installed or not
    sys.path.insert(0, str(ROOT / "src"))

DEFAULT_JSON = ROOT / "benchmarks" / "results" / "latest.json"
REPEATS, QUICK_REPEATS = 5, 2


def timed(fn: Callable, *args):
    """(fn(*args), wall seconds), waiting for JAX's asynchronous dispatch."""
    import jax

    t0 = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    return out, time.perf_counter() - t0


def time_jitted(fn: Callable, args: Sequence, repeats: int) -> tuple[object, dict]:
    """Time a jitted ``fn``: first call, then the median of ``repeats`` calls.

    Returns the last output and {compile_s, run_s, run_s_all}; compile_s is the
    first call minus the steady run time.
    """
    out, first = timed(fn, *args)
    runs = []
    for _ in range(repeats):
        out, wall = timed(fn, *args)
        runs.append(wall)
    run = statistics.median(runs)
    return out, {"compile_s": max(first - run, 0.0), "run_s": run, "run_s_all": runs}


def _git_commit() -> str | None:
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                             capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None


def metadata(quick: bool) -> dict:
    import jax

    import diffwear

    return {
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "quick": quick,
        "commit": _git_commit(),
        "diffwear": diffwear.__version__,
        "jax": jax.__version__,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "device": str(jax.devices()[0]),
        "cpu_count": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0] if hasattr(os, "getloadavg") else None,
    }


def run_cases(cases: Mapping[str, Callable[[int], dict]], names: Sequence[str] | None = None,
              *, quick: bool = False, log=print) -> dict:
    """Run the named ``cases`` (default: all) -> {"meta": ..., "cases": {name: metrics}}."""
    import jax

    jax.config.update("jax_enable_x64", True)  # diffwear computes in float64
    names = list(cases) if not names else list(names)
    unknown = [n for n in names if n not in cases]
    if unknown:
        raise KeyError(f"unknown benchmark case(s) {unknown}; available: {list(cases)}")
    repeats = QUICK_REPEATS if quick else REPEATS
    results = {"meta": metadata(quick), "cases": {}}
    for name in names:
        log(f"[bench] {name} ({repeats} repeats) ...", file=sys.stderr)
        results["cases"][name] = cases[name](repeats)
    return results


COLUMNS = (  # metric key, header, format
    ("compile_s", "compile [s]", "{:.2f}"),
    ("run_s", "run, median [s]", "{:.3f}"),
    ("run_s_per_simulated_s", "run per simulated s", "{:.3f}"),
    ("integrator_steps", "integrator steps", "{:d}"),
    ("us_per_step", "µs per step", "{:.0f}"),
    ("dynamic_cycles", "dynamic cycles", "{:d}"),
    ("run_s_per_cycle", "run per dynamic cycle [s]", "{:.3f}"),
    ("points_per_s_unordered", "sweep points/s", "{:.1f}"),
    ("ratio_sweep_unordered_to_single", "sweep / single runs", "{:.2f}"),
    ("ratio_gradient_to_forward", "gradient / forward", "{:.1f}"),
    ("speedup_per_cycle", "peer / diffwear per cycle", "{:.1f}"),
    ("ratio_fem_to_efm", "FEM / EFM route", "{:.2f}"),
    ("ratio_lubricated_to_dry", "lubricated / dry", "{:.2f}"),
    ("note", "note", "{}"),
)


def markdown(results: dict) -> str:
    lines = ["| case | " + " | ".join(h for _, h, _ in COLUMNS) + " |",
             "|---|" + "---:|" * len(COLUMNS)]
    for name, m in results["cases"].items():
        cells = [fmt.format(m[key]) if key in m else "" for key, _, fmt in COLUMNS]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    meta = results["meta"]
    load = meta["load_average_1min"]
    load = "n/a" if load is None else f"{load:.1f}"
    lines.append(f"\n{meta['device']}, {meta['cpu_count']} CPUs, 1-min load {load}; "
                 f"jax {meta['jax']}, commit {meta['commit']}; "
                 f"{'quick' if meta['quick'] else 'full'} run")
    return "\n".join(lines)


def write_results(results: dict, path: Path) -> None:
    """The results as indented JSON at ``path`` (its folder made as needed)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(results, indent=2) + "\n")
