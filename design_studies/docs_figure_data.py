#!/usr/bin/env python3
"""Stored runs of the thesis studies, for the documentation's figures.

The documentation draws its figures at build time from stored data only (no
simulation while the site builds).  This script runs the named studies
(``diffwear study NAME``), each into its own folder, and copies the small
files the figures read into ``design_studies/results/studies/NAME/``: the
summary and the curves, long time series thinned to at most
``MAX_ROWS`` rows (the figures are ~700 px wide: more points draw nothing
more).  Rerun it after a change of the model; the figures follow.

    .venv/bin/python design_studies/docs_figure_data.py            # all: ~17 min on 2 shared cores
    .venv/bin/python design_studies/docs_figure_data.py --only rig-21400
    .venv/bin/python design_studies/docs_figure_data.py --runs DIR  # copy runs already in DIR/NAME

Runs (the study, its options, the files kept):

* ``ideal-slider-crank`` (Ch. 2): the crank-rod reaction and the Baumgarte drift;
* ``clearance-sweep`` (Ch. 3/6): the joint force of every law and clearance and
  the ideal joint's, the contact loci;
* ``wear-5000`` (Ch. 5-6), ``rig-21400`` (Ch. 7): profile, history, the first
  and last cycles' joint force and pin locus, on the dynamic model;
* ``rig-21400-fem`` (Ch. 5/7): ``rig-21400 --contact fem``, the FEM route's profile;
* ``pin-pivot`` (Ch. 4): the pin and pivot profiles and the max-wear history;
* ``sweep-rig-clearance-k``: ``diffwear sweep design_studies/sweep_rig_clearance_k.toml``
  on the quasi-static joint model, its results table.
"""

from __future__ import annotations

import argparse
import csv
import inspect
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STORE = ROOT / "design_studies" / "results" / "studies"
# A figure is ~700 px wide at 100-120 dpi: 400 intervals per curve draw it fully.
MAX_ROWS = 401
SIGNIFICANT = 6  # digits kept per value: 1e-6 relative, below a figure's line width

# stored name -> (study, study options, files kept (glob patterns), seconds kept
# at the end of a time series (None: all))
RUNS = {
    "ideal-slider-crank": ("ideal-slider-crank", {},
                           ("summary.json", "reaction_crank_rod.csv",
                            "constraint_violation.csv"), None),
    # the last of the three crank cycles (2 s at pi rad/s), as the study's own
    # figures; the loci at the largest Table 3-2 clearance (5 mm) only
    "clearance-sweep": ("clearance-sweep", {},
                        ("summary.json", "force_*.csv", "locus_*_5.csv"), 2.0),
    "wear-5000": ("wear-5000", {},
                  ("summary.json", "wear_profile.csv", "wear_history.csv",
                   "joint_force_*_cycle.csv", "contact_locus_*_cycle.csv"), None),
    "rig-21400": ("rig-21400", {},
                  ("summary.json", "wear_profile.csv", "wear_history.csv",
                   "joint_force_*_cycle.csv", "contact_locus_*_cycle.csv"), None),
    "rig-21400-fem": ("rig-21400", {"contact": "fem"},
                      ("summary.json", "wear_profile*.csv", "wear_history*.csv"), None),
    "pin-pivot": ("pin-pivot", {}, ("summary.json", "profiles.csv", "history.csv"), None),
    # `diffwear sweep design_studies/sweep_rig_clearance_k.toml` on the
    # quasi-static joint model (seconds instead of minutes; within 0.1 % of the
    # dynamic model on the rig: benchmarks/records/agreement.json)
    "sweep-rig-clearance-k": (None, {"wear_model": "quasi-static"},
                              ("summary.json", "results.csv"), None),
}
SWEEP_FILE = ROOT / "design_studies" / "sweep_rig_clearance_k.toml"


def thin_csv(source: Path, target: Path, last_s: float | None = None,
             max_rows: int = MAX_ROWS) -> None:
    """Copy a CSV keeping its header, its first and last rows and evenly
    spaced rows between, at most ``max_rows`` data rows, each value to
    `SIGNIFICANT` digits; ``last_s``: only the rows of the last ``last_s``
    seconds of its ``t_s`` column."""
    with open(source, newline="") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], rows[1:]
    if last_s is not None and "t_s" in header:
        k = header.index("t_s")
        end = float(data[-1][k])
        data = [r for r in data if float(r[k]) >= end - last_s - 1e-9]
    data = [[f"{float(v):.{SIGNIFICANT}g}" for v in r] for r in data]
    if len(data) > max_rows:
        step = -(-(len(data) - 1) // (max_rows - 1))
        data = data[::step] + ([data[-1]] if (len(data) - 1) % step else [])
    with open(target, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows([header, *data])


def store(name: str, run_dir: Path) -> list[Path]:
    """Copy run ``name``'s kept files from ``run_dir`` into the store."""
    target = STORE / name
    if target.exists():
        shutil.rmtree(target)
    target.mkdir(parents=True)
    kept = []
    _, _, patterns, last_s = RUNS[name]
    for pattern in patterns:
        matches = sorted(run_dir.glob(pattern))
        if not matches:
            raise FileNotFoundError(f"{run_dir}: the study wrote no {pattern}")
        for path in matches:
            if path.suffix == ".csv":
                thin_csv(path, target / path.name, last_s)
            else:
                shutil.copyfile(path, target / path.name)
            kept.append(target / path.name)
    return kept


def run(name: str, folder: Path) -> Path:
    """Run the study of stored run ``name`` into ``folder / name``."""
    sys.path.insert(0, str(ROOT / "src"))
    import jax

    jax.config.update("jax_enable_x64", True)  # diffwear computes in float64
    from diffwear.io import OutputDir
    from diffwear.studies import STUDIES

    study, options, _, _ = RUNS[name]
    out = folder / name
    if study is None:  # the sweep file, its settings amended by the options
        text = SWEEP_FILE.read_text()
        extra = "".join(f'{k} = "{v}"\n' for k, v in options.items())
        sweep_file = folder / SWEEP_FILE.name
        sweep_file.write_text(text.replace("[settings]\n", "[settings]\n" + extra, 1))
        subprocess.run([sys.executable, "-m", "diffwear.cli", "sweep", str(sweep_file),
                        "--out", str(out), "--quiet"], check=True,
                       env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
        return out
    kwargs = {}
    if options:  # the study's model from the command line's options (`diffwear study`)
        from diffwear.cli.command import study_model

        cycles = inspect.signature(STUDIES[study].run).parameters["cycles"].default
        kwargs["model"] = study_model(STUDIES[study], cycles, options)
    STUDIES[study].run(OutputDir(out), log=lambda *a: None, **kwargs)
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", choices=sorted(RUNS), help="these runs only")
    parser.add_argument("--runs", type=Path,
                        help="copy the runs already in RUNS/NAME instead of running them")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.only or RUNS:
            t0 = time.perf_counter()
            source = args.runs / name if args.runs else run(name, Path(tmp))
            kept = store(name, source)
            size = sum(p.stat().st_size for p in kept)
            print(f"{name}: {len(kept)} files, {size / 1e3:.0f} kB, "
                  f"{time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
