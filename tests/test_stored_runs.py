"""The documentation's figures are drawn from stored runs
(``design_studies/results/studies/``, written by
``design_studies/docs_figure_data.py``); a fresh run of the same study must
give the same figure data, so that the stored copies cannot drift from the
code.  Each run below is the script's own (`run`, then its thinning of the
curves, `thin_csv`), compared with the stored files: every column of every
stored CSV, and every number of the stored summary except times and file
lists.  Stored values carry 6 significant digits (`SIGNIFICANT`), so a
column matches within a last-digit flip (2e-5 of the value) or a floor of its
largest value: 1e-4 for the wear's histories and profiles (integrals over
the run), 3e-2 for the forces and pin loci of one cycle (`ONE_CYCLE`).  A
clearance joint's impacts amplify rounding: the same code and jaxlib on two
machines gave the rig's one-cycle curves 1.2e-2 of a column's largest value
apart (its joint force fy_N; the pin's offset 9e-3), its wear histories
1.4e-5 and its summary numbers 1.5e-6 of the value apart.

The rig's study (the site's main figures, ~1 min) runs under ``--extended``
(CI); the others (up to ~5 min each) under ``--long``."""

from __future__ import annotations

import csv
import importlib.util
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "design_studies" / "docs_figure_data.py"
RTOL = 2e-5    # a last-digit flip of a 6-digit value: <= 1e-5 of it
FLOOR = 1e-4   # of a column's largest |value|: an integral over the run (7x the measured 1.4e-5)
# files of one cycle's curves (forces, pin locus): 2.5x the measured 1.2e-2
ONE_CYCLE = ("_first_cycle", "_last_cycle")
ONE_CYCLE_FLOOR = 3e-2
SUMMARY_RTOL = 1e-5  # a summary number (7x the measured 1.5e-6)
# summary.json keys that change from run to run or name files, not results
UNSTABLE = ("wall_time", "compile_time", "time_s", "_s", "files", "checkpoint", "file",
            "resumed_from_cycles", "wall_time_ratio")


def _script():
    spec = importlib.util.spec_from_file_location("docs_figure_data", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("docs_figure_data", module)
    spec.loader.exec_module(module)
    return module


def _columns(path: Path) -> dict[str, np.ndarray]:
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: np.array([float(r[k]) for r in rows[1:]]) for k, name in enumerate(rows[0])}


def _numbers(tree, prefix: str = "") -> dict[str, float]:
    """The numeric leaves of a summary by their path, times and files left out."""
    out: dict[str, float] = {}
    if isinstance(tree, dict):
        for k, v in tree.items():
            if not any(k.endswith(u) or k.startswith(u) for u in UNSTABLE):
                out |= _numbers(v, f"{prefix}{k}.")
    elif isinstance(tree, list):
        for k, v in enumerate(tree):
            out |= _numbers(v, f"{prefix}{k}.")
    elif isinstance(tree, (int, float)) and not isinstance(tree, bool):
        out[prefix.rstrip(".")] = float(tree)
    return out


def _assert_same_figure_data(name: str, fresh_dir: Path, thinned: Path) -> int:
    """Every stored file of run ``name`` against the fresh run's (thinned as
    the script thins it); returns the number of values compared."""
    script = _script()
    stored_dir = script.STORE / name
    last_s = script.RUNS[name][3]
    compared = 0
    for stored in sorted(stored_dir.iterdir()):
        if stored.suffix == ".csv":
            fresh = thinned / stored.name
            script.thin_csv(fresh_dir / stored.name, fresh, last_s)
            a, b = _columns(stored), _columns(fresh)
            assert list(a) == list(b), (stored.name, list(a), list(b))
            for col, x in a.items():
                y = b[col]
                assert x.shape == y.shape, (stored.name, col, x.shape, y.shape)
                share = ONE_CYCLE_FLOOR if stored.stem.endswith(ONE_CYCLE) else FLOOR
                floor = share * float(np.max(np.abs(x), initial=0.0))
                np.testing.assert_allclose(y, x, rtol=RTOL, atol=floor,
                                           err_msg=f"{name}/{stored.name}: {col}")
                compared += x.size
        elif stored.name == "summary.json":
            a = _numbers(json.loads(stored.read_text()))
            b = _numbers(json.loads((fresh_dir / "summary.json").read_text()))
            assert set(a) == set(b), sorted(set(a) ^ set(b))
            for key, x in a.items():
                assert math.isclose(b[key], x, rel_tol=SUMMARY_RTOL, abs_tol=1e-12), \
                    (name, key, x, b[key])
            compared += len(a)
    return compared


def _fresh(name: str, tmp_path: Path) -> int:
    script = _script()
    run_dir = script.run(name, tmp_path / "runs")
    thinned = tmp_path / "thinned"
    thinned.mkdir()
    return _assert_same_figure_data(name, run_dir, thinned)


@pytest.mark.extended  # ~1 min: the rig's dynamic study, compiled and run
def test_a_fresh_rig_run_gives_the_stored_figure_data(tmp_path):
    assert _fresh("rig-21400", tmp_path) > 4000


@pytest.mark.long  # minutes each
@pytest.mark.parametrize("name", ["ideal-slider-crank", "clearance-sweep", "wear-5000",
                                  "rig-21400-fem", "pin-pivot", "sweep-rig-clearance-k"])
def test_a_fresh_run_gives_the_stored_figure_data(name, tmp_path):
    assert _fresh(name, tmp_path) > 0


def test_every_stored_run_is_checked_against_a_fresh_one():
    """The two tests above cover every run the script stores."""
    covered = {"rig-21400", "ideal-slider-crank", "clearance-sweep", "wear-5000",
               "rig-21400-fem", "pin-pivot", "sweep-rig-clearance-k"}
    assert covered == set(_script().RUNS)


def test_the_comparison_tells_a_changed_curve_from_rounding(tmp_path):
    """The comparison itself: the stored rig profile written again at 6
    digits passes; the same with its deepest value moved by 1e-3 (10x the
    histories' floor) fails, and so does one cycle's largest force moved by
    6 % (2x the one-cycle floor)."""
    script = _script()
    stored = script.STORE / "rig-21400" / "wear_profile.csv"
    fresh_dir = tmp_path / "fresh"
    fresh_dir.mkdir()
    (fresh_dir / "summary.json").write_text((stored.parent / "summary.json").read_text())
    for f in stored.parent.glob("*.csv"):
        (fresh_dir / f.name).write_text(f.read_text())
    (tmp_path / "a").mkdir()
    assert _assert_same_figure_data("rig-21400", fresh_dir, tmp_path / "a") > 1000
    _move_largest(stored, "depth_mm", 1 + 1e-3, fresh_dir / stored.name)
    (tmp_path / "b").mkdir()
    with pytest.raises(AssertionError, match="wear_profile.csv: depth_mm"):
        _assert_same_figure_data("rig-21400", fresh_dir, tmp_path / "b")
    (fresh_dir / stored.name).write_text(stored.read_text())
    force = stored.parent / "joint_force_first_cycle.csv"
    _move_largest(force, "force_N", 1.06, fresh_dir / force.name)
    (tmp_path / "c").mkdir()
    with pytest.raises(AssertionError, match="joint_force_first_cycle.csv: force_N"):
        _assert_same_figure_data("rig-21400", fresh_dir, tmp_path / "c")


def _move_largest(stored: Path, column: str, factor: float, out: Path) -> None:
    """``stored`` written to ``out`` with ``column``'s largest value times
    ``factor`` (at the stored 6 digits)."""
    rows = stored.read_text().splitlines()
    head, values = rows[0], [r.split(",") for r in rows[1:]]
    col = head.split(",").index(column)
    k = int(np.argmax([float(v[col]) for v in values]))
    values[k][col] = f"{float(values[k][col]) * factor:.6g}"
    out.write_text("\n".join([head, *map(",".join, values)]) + "\n")
