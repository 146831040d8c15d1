"""Calibrate every shipped campaign and store the runs the docs show.

Each dataset folder next to this script is calibrated with the command a
user would type (`diffwear calibrate DATASET --out results/NAME`), its log
kept beside it as ``results/NAME.log``; the calibration guide's results table
and figures are read from there.

    python design_studies/calibration/run_all.py [--only NAME ...] [--jobs 2]
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "results"


def datasets() -> list[str]:
    return sorted(p.parent.name for p in HERE.glob("*/dataset.toml"))


def calibrate(name: str, extra: list[str]) -> int:
    RESULTS.mkdir(exist_ok=True)
    # the stored run is this script's own output: replaced whole (a run of an
    # earlier version may lack the files' list that --overwrite reads)
    shutil.rmtree(RESULTS / name, ignore_errors=True)
    cmd = [sys.executable, "-m", "diffwear.cli", "calibrate", str(HERE / name),
           "--out", str(RESULTS / name), *extra]
    with open(RESULTS / f"{name}.log", "w") as log:
        rc = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT)
    print(f"{name}: exit {rc}", flush=True)
    return rc


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", default=None, help="dataset names")
    ap.add_argument("--jobs", type=int, default=1, help="calibrations at once")
    args, extra = ap.parse_known_args(argv)
    names = datasets() if not args.only else [n for n in args.only if n in datasets()]
    with ThreadPoolExecutor(args.jobs) as pool:
        codes = list(pool.map(lambda n: calibrate(n, extra), names))
    return max(codes, default=0)


if __name__ == "__main__":
    sys.exit(main())
