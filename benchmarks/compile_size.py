#!/usr/bin/env python3
"""What a mechanism file's size costs before it runs: time and peak memory.

    python benchmarks/compile_size.py [--json PATH] [--quick]

``diffwear run FILE`` traces and compiles the file's mechanism once per run;
the traced program grows with every joint and force element (each is its own
piece of the constraint and force functions) and with the coordinates.  This
script writes two families of files, runs each through the command (a fresh
process, so its time includes the start-up, the compilation and the short
run) and records the wall time and the process's peak resident memory:

* ``free N``: N free bodies under gravity (3N coordinates, no constraint);
* ``chain N``: an N-link pendulum, each link pinned to the one before (3N
  coordinates, N revolute joints).

It then fits, by least squares, ``seconds = a + b elements + c coordinates``
and ``memory = a + b elements^2 + c coordinates``: the coefficients
`diffwear.mechanism_file.size` uses to warn about, or refuse, a file before
compiling it.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_JSON = ROOT / "benchmarks" / "records" / "compile_size.json"
CASES = [("free", 100), ("free", 1000), ("free", 3000),
         ("chain", 10), ("chain", 50), ("chain", 100), ("chain", 200)]
QUICK = [("free", 100), ("chain", 10), ("chain", 25)]


def mechanism_text(kind: str, n: int) -> str:
    """A file of ``n`` bodies: free ones 1 m apart, or a chain of 0.2 m links."""
    lines = [f'title = "{kind} {n}"', ""]
    for i in range(n):
        lines += ["[[bodies]]", f'name = "b{i}"', 'mass = "1 kg"', 'inertia = "0.01 kg m^2"', ""]
    if kind == "chain":
        for i in range(n):
            parent, point = ("ground", "0 m") if i == 0 else (f"b{i - 1}", "0.1 m")
            lines += ["[[joints]]", 'type = "revolute"', f'name = "j{i}"', f'body_i = "b{i}"',
                      f'body_j = "{parent}"', 'point_i = ["-0.1 m", "0 m"]',
                      f'point_j = ["{point}", "0 m"]', ""]
    lines += ["[[forces]]", 'type = "gravity"', 'g = ["0 m/s^2", "-9.80665 m/s^2"]', "",
              "[initial]"]
    for i in range(n):
        x = 0.1 + 0.2 * i if kind == "chain" else float(i)
        lines.append(f'b{i} = {{ x = "{x} m", y = "0 m", phi = "0 deg" }}')
    lines += ["", "[simulation]", 'duration = "0.01 s"', "n_save = 11", ""]
    return "\n".join(lines)


def measure(kind: str, n: int, folder: Path) -> dict:
    path = folder / f"{kind}{n}.toml"
    path.write_text(mechanism_text(kind, n))
    exe = Path(sys.executable).with_name("diffwear")
    t0 = time.perf_counter()
    proc = subprocess.Popen([str(exe), "run", str(path), "--out", str(folder / f"out-{kind}{n}"),
                             "--quiet"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    seconds = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise RuntimeError(f"{kind} {n}: exit {proc.returncode}: {proc.stderr.read()[-2000:]}")
    scale = 1 if sys.platform == "darwin" else 1024  # ru_maxrss: bytes on macOS, KiB on Linux
    elements = (n if kind == "chain" else 0) + 1  # the joints and the gravity element
    return {"kind": kind, "bodies": n, "elements": elements, "coordinates": 3 * n,
            "seconds": round(seconds, 2), "peak_bytes": usage.ru_maxrss * scale}


def fit(rows: list[dict]) -> dict:
    import numpy as np

    e = np.array([r["elements"] for r in rows], float)
    c = np.array([r["coordinates"] for r in rows], float)
    ones = np.ones_like(e)
    time_coef = np.linalg.lstsq(np.column_stack([ones, e, c]),
                                np.array([r["seconds"] for r in rows]), rcond=None)[0]
    mem_coef = np.linalg.lstsq(np.column_stack([ones, e ** 2, c]),
                               np.array([r["peak_bytes"] for r in rows], float), rcond=None)[0]
    return {"seconds": {"base": time_coef[0], "per_element": time_coef[1],
                        "per_coordinate": time_coef[2]},
            "bytes": {"base": mem_coef[0], "per_element_squared": mem_coef[1],
                      "per_coordinate": mem_coef[2]}}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path, default=DEFAULT_JSON)
    ap.add_argument("--quick", action="store_true", help="three small files (a smoke run)")
    args = ap.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for kind, n in QUICK if args.quick else CASES:
            rows.append(measure(kind, n, Path(tmp)))
            r = rows[-1]
            print(f"{kind:>5} {n:>5} bodies  {r['elements']:>4} elements  {r['seconds']:7.1f} s  "
                  f"{r['peak_bytes'] / 1e9:6.2f} GB", flush=True)
    coef = fit(rows)
    print(json.dumps(coef, indent=2))
    record = {"date": datetime.date.today().isoformat(), "machine": platform.platform(),
              "cpus": os.cpu_count(), "python": platform.python_version(),
              "what": "diffwear run FILE --quiet in a fresh process: wall time and peak RSS",
              "rows": rows, "fit": coef}
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(record, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
