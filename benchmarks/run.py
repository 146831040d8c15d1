#!/usr/bin/env python3
"""diffwear performance benchmarks.

    python benchmarks/run.py [--quick] [--json PATH] [--case NAME ...]

Each registered case (`CASES`: name -> function(repeats) -> metrics) builds
its problem, times the first call of its jitted function (compile + run) and
``repeats`` steady calls, and returns a flat dict of metrics.  The table goes
to stdout as markdown, the full results (with machine and version metadata)
to JSON, by default ``benchmarks/results/latest.json`` (gitignored).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
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


# ------------------------------------------------------------------- cases
def ideal_slider_crank(repeats: int) -> dict:
    """Thesis Table 2-1 slider-crank, 2 s (one revolution), the study's settings:
    Tsit5, rtol = atol = 1e-8, Baumgarte 250 1/s, 801 saved times."""
    import jax
    import jax.numpy as jnp

    from diffwear.dynamics import consistent_state, simulate
    from diffwear.presets import TABLE_2_1, slider_crank

    duration = 2.0  # s
    mech, q_guess = slider_crank(TABLE_2_1)
    y0 = consistent_state(mech, q_guess)
    ts = jnp.linspace(0.0, duration, 801)
    sim = jax.jit(lambda m, y: simulate(m, y, duration, ts=ts))
    traj, metrics = time_jitted(sim, (mech, y0), repeats)
    traj.raise_if_failed("benchmark ideal slider-crank")
    return {
        "simulated_s": duration,
        **metrics,
        "run_s_per_simulated_s": metrics["run_s"] / duration,
        "integrator_steps": int(traj.num_steps),
        "repeats": repeats,
    }


CASES: dict[str, Callable[[int], dict]] = {
    "ideal slider-crank, 2 s": ideal_slider_crank,
}


# ---------------------------------------------------------------- harness
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


def run_cases(names: Sequence[str] | None = None, *, quick: bool = False, log=print) -> dict:
    """Run the named cases (default: all) -> {"meta": ..., "cases": {name: metrics}}."""
    names = list(CASES) if not names else list(names)
    unknown = [n for n in names if n not in CASES]
    if unknown:
        raise KeyError(f"unknown benchmark case(s) {unknown}; available: {list(CASES)}")
    repeats = QUICK_REPEATS if quick else REPEATS
    results = {"meta": metadata(quick), "cases": {}}
    for name in names:
        log(f"[bench] {name} ({repeats} repeats) ...", file=sys.stderr)
        results["cases"][name] = CASES[name](repeats)
    return results


COLUMNS = (  # metric key, header, format
    ("compile_s", "compile [s]", "{:.2f}"),
    ("run_s", "run, median [s]", "{:.3f}"),
    ("run_s_per_simulated_s", "run per simulated s", "{:.3f}"),
    ("integrator_steps", "integrator steps", "{:d}"),
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
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(results, indent=2) + "\n")
    print(f"\nwrote {args.json}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
