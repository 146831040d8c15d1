"""``diffwear sweep FILE.toml``: a tiny rig sweep end to end, and bad input.

The end-to-end run (2 x 3 points of the rig at 2 cycles, n_theta 24) is
compile-bound (~30 s on 2 cores under load), hence slow; every bad-input case
fails before anything is compiled.
"""

import csv
import json

import numpy as np
import pytest

from diffwear.cli import main
from diffwear.config.sweep import load_sweep
from diffwear.wear.status import RESULTS, code

TINY = '''
title = "tiny rig"
model = "rig-wear"
[settings]
cycles = 2
dynamic_cycles = 1
n_theta = 24
force_samples = 13
[base]
mu = 0.13
[grid]
clearance = ["0.02 mm", "50 um"]
k = { start = "0.05 mm^3/(N m)", stop = "0.1 mm^3/(N m)", num = 3 }
'''


@pytest.fixture(scope="module")
def tiny_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("sweep")
    (root / "tiny.toml").write_text(TINY)
    out = root / "out"
    assert main(["sweep", str(root / "tiny.toml"), "--out", str(out), "--quiet",
                 "--device", "cpu"]) == 0
    return out


@pytest.mark.slow
def test_tiny_sweep_outputs(tiny_dir):
    """Every file is written; the CSV, NPZ, NetCDF and summary agree; the units
    were converted (0.05 mm^3/(N m) = 5e-11 1/Pa, 50 um = 5e-5 m); and the worn
    volume is proportional to k (Archard, at fixed clearance: the profile
    hardly changes the load in 2 cycles; independent of the simulation)."""
    summary = json.loads((tiny_dir / "summary.json").read_text())
    for name in summary["files"]:
        assert (tiny_dir / name).is_file(), name
    for name in ("max_depth_mm.png", "volume_mm3.png", "mean_joint_force_N.png"):
        assert (tiny_dir / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    assert summary["grid_shape"] == [2, 3] and summary["points"] == 6
    assert summary["failed_points"] == [] and summary["device"] == "cpu"
    assert summary["execution"] in ("looped", "pooled") and summary["chunk_size"] == 1
    np.testing.assert_allclose(summary["grid_si"]["clearance_m"], [2e-5, 5e-5], rtol=1e-15)
    np.testing.assert_allclose(summary["grid_si"]["k_per_Pa"], [5e-11, 7.5e-11, 1e-10],
                               rtol=1e-15)
    with open(tiny_dir / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 6 and {"clearance_m", "k_per_Pa", "mu", "volume_mm3"} <= set(rows[0])
    assert float(rows[1]["clearance_m"]) == 2e-5 and float(rows[1]["k_per_Pa"]) == 7.5e-11
    vol = np.array([float(r["volume_mm3"]) for r in rows]).reshape(2, 3)
    npz = np.load(tiny_dir / "results.npz")
    np.testing.assert_array_equal(npz["volume_mm3"].reshape(2, 3), vol)  # full precision
    np.testing.assert_array_equal(npz["axis_k"], [5e-11, 7.5e-11, 1e-10])
    assert summary["outputs"]["volume_mm3"]["max"] == vol.max()
    np.testing.assert_allclose(vol / vol[:, :1], [[1, 1.5, 2]] * 2, rtol=2e-3)
    assert np.all(vol > 0)
    if summary["netcdf"] == "results.nc":
        from scipy.io import netcdf_file

        with netcdf_file(tiny_dir / "results.nc", "r", mmap=False) as nc:
            np.testing.assert_array_equal(nc.variables["volume_mm3"][:], vol)
            np.testing.assert_array_equal(nc.variables["clearance"][:], [2e-5, 5e-5])
    report = (tiny_dir / "report.md").read_text()
    assert report.startswith("# sweep: tiny rig") and "](volume_mm3.png)" in report
    assert "Run one point after another" in report and "on the CPU" in report


@pytest.mark.slow
def test_existing_out_not_overwritten(tiny_dir, capsys):
    before = {p.name: p.read_bytes() for p in tiny_dir.iterdir()}
    assert main(["sweep", str(tiny_dir.parent / "tiny.toml"), "--out", str(tiny_dir),
                 "--quiet"]) == 2
    assert "already holds results" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in tiny_dir.iterdir()} == before


def test_device_options_that_cannot_be_met_are_refused_before_anything_runs(tmp_path, capsys):
    import jax

    f = tmp_path / "tiny.toml"
    f.write_text(TINY)
    out = tmp_path / "out"
    if not any(d.platform == "gpu" for d in jax.devices()):
        assert main(["sweep", str(f), "--out", str(out), "--device", "gpu", "--quiet"]) == 2
        assert "--device gpu: JAX sees no GPU here" in capsys.readouterr().err
    assert main(["sweep", str(f), "--out", str(out), "--device", "cpu", "--workers", "2",
                 "--quiet"]) == 2
    assert "--device cpu belongs to a sweep on this machine" in capsys.readouterr().err
    assert not out.exists()


def _bad(tmp_path, capsys, text):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    out = tmp_path / "out"
    code = main(["sweep", str(f), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert not out.exists()  # nothing written before the input is checked
    return code, err


GOOD_GRID = '[grid]\nclearance = ["0.02 mm"]\n'


@pytest.mark.parametrize("text, message", [
    ('model = "rig-waer"\n' + GOOD_GRID,
     "model: unknown model 'rig-waer' (did you mean 'rig-wear'?); allowed: 'rig-wear', "
     "'clearance-force'"),
    ('model = "rig-wear"\n[grid]\nclearence = ["0.02 mm"]\n',
     "grid.clearence: unknown key 'clearence' (did you mean 'clearance'?)"),
    ('model = "rig-wear"\n[grid]\nclearance = [0.02]\n',
     "grid.clearance[0]: bare number 0.02 has no unit"),
    ('model = "rig-wear"\n[grid]\nclearance = ["0.02"]\n',
     "grid.clearance[0]: '0.02' has no unit"),
    ('model = "rig-wear"\n[grid]\nclearance = ["0.02 mm", "0 mm"]\n',
     "grid.clearance[1]: '0 mm' = 0 m is out of range; allowed: > 0 m"),
    ('model = "rig-wear"\n[grid]\nk = ["-5e-4 mm^3/(N m)"]\n',
     "grid.k[0]: '-5e-4 mm^3/(N m)' = -5e-13 1/Pa is out of range; allowed: > 0 1/Pa"),
    ('model = "rig-wear"\n[grid]\nclearance = []\n',
     "grid.clearance: the axis is empty; allowed: one or more values"),
    ('model = "rig-wear"\n[grid]\nclearance = ["0.02 kg"]\n',
     "grid.clearance[0]: unit 'kg' is a mass unit, not length"),
    ('model = "rig-wear"\n[grid]\nmu = { start = 0.1, stop = 1.5, num = 3 }\n',
     "grid.mu.stop: 1.5 is out of range; allowed: [0, 1]"),
    ('model = "rig-wear"\n[grid]\n',
     "grid: no axis; allowed: one or more of k, clearance"),
    ('model = "rig-wear"\n',
     "grid: missing section"),
    ('model = "rig-wear"\n[settings]\nn_theta = 4\n' + GOOD_GRID,
     "settings.n_theta: 4 is out of range; allowed: [8, 3600]"),
    ('model = "rig-wear"\n[settings]\ncycles = 10\ndynamic_cycles = 20\n' + GOOD_GRID,
     "settings.dynamic_cycles: 20 > cycles = 10"),
    ('model = "rig-wear"\n[base]\nclearance = "0.02 mm"\n' + GOOD_GRID,
     "grid.clearance: also given in [base]"),
    ('model = "clearance-force"\n[grid]\nk = ["5e-4 mm^3/(N m)"]\n',
     "grid.k: unknown key 'k'; allowed: clearance, mu, restitution, pin_radius (parameters "
     "of model 'clearance-force')"),
])
def test_bad_input_exit_2(tmp_path, capsys, text, message):
    code, err = _bad(tmp_path, capsys, text)
    assert code == 2
    assert f"bad.toml: {message}" in err, err


def test_bad_options_and_missing_file(tmp_path, capsys):
    f = tmp_path / "ok.toml"
    f.write_text('model = "rig-wear"\n' + GOOD_GRID)
    assert main(["sweep", str(f), "--out", str(tmp_path / "o"), "--chunk-size", "0"]) == 2
    assert "--chunk-size must be an integer in [1, 100,000], got 0" in capsys.readouterr().err
    assert main(["sweep", str(tmp_path / "nope.toml"), "--out", str(tmp_path / "o")]) == 2
    assert "nope.toml: no such file" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_example_file_loads():
    """The shipped example: 4 x 4 points of the thesis rig, units converted."""
    from pathlib import Path

    spec = load_sweep(Path(__file__).resolve().parents[1] / "design_studies"
                      / "sweep_rig_clearance_k.toml")
    assert spec.points == 16 and spec.model.cycles == 21_400.0 and spec.chunk_size == 8
    np.testing.assert_allclose(spec.grid["clearance"], [2e-5, 3.3e-5, 5e-5, 1e-4], rtol=1e-15)
    np.testing.assert_allclose(spec.grid["k"][[0, -1]], [2.525e-13, 7.575e-13], rtol=1e-12)
    np.testing.assert_allclose(spec.grid["k"][1] / spec.grid["k"][0],
                               3 ** (1 / 3), rtol=1e-12)  # geometric: ratio^3 = 3
    assert spec.base["mu"] == 0.13 and spec.base["depth"] == pytest.approx(13.1e-3)


def test_help_lists_sweep(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["sweep", "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "--chunk-size" in out and "--cluster" in out and "Exit codes" in out



def _code(member: str) -> float:
    """A sweep table's status: the code of the `RESULTS` member ``member``."""
    return float(code(getattr(RESULTS, member)))

class _Fragile:
    """A cheap stand-in for the rig model: fails (NaN) for clearance > 0.04 mm."""

    param_names = ("k", "clearance", "depth", "diameter", "mu", "free_length")

    def __init__(self, **settings):
        pass

    @property
    def defaults(self):
        from diffwear.sweep.models import RigWear

        return RigWear().defaults

    def __call__(self, p):
        import jax.numpy as jnp

        depth = p["k"] * 1e9 * p["clearance"] * 1e3
        return {"max_depth_mm": jnp.where(p["clearance"] > 0.04e-3, jnp.nan, depth),
                "status": jnp.where(p["clearance"] > 0.04e-3, _code("cycle_model_failed"),
                                    _code("ok"))}


def test_failed_points_exit_3_and_results_kept(tmp_path, capsys, monkeypatch):
    """A point whose outputs are NaN / the cycle model failed: exit 3 naming it, and the
    other points' results are still written."""
    import dataclasses

    from diffwear.config import sweep as cfg

    monkeypatch.setitem(cfg.MODELS, "rig-wear",
                        dataclasses.replace(cfg.MODELS["rig-wear"], build=_Fragile))
    f = tmp_path / "s.toml"
    f.write_text('model = "rig-wear"\n[grid]\nclearance = ["0.02 mm", "0.05 mm"]\n')
    out = tmp_path / "out"
    assert main(["sweep", str(f), "--out", str(out), "--quiet"]) == 3
    err = capsys.readouterr().err
    assert "1 of 2 sweep points failed" in err and "'clearance': 5e-05" in err
    assert "cycle_model_failed: the cycle model failed" in err  # why, in words
    summary = json.loads((out / "summary.json").read_text())
    assert summary["failed_points"] == [1]
    with open(out / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert float(rows[0]["max_depth_mm"]) == pytest.approx(5.05e-4 * 0.02)  # k[mm^3/Nm] x c[mm]
    assert rows[1]["max_depth_mm"] == "nan"


class _Linear(_Fragile):
    """Depth = k [mm^3/(N m)] x clearance [mm]: a closed form, every point ok."""

    def __call__(self, p):
        import jax.numpy as jnp

        return {"max_depth_mm": p["k"] * 1e9 * p["clearance"] * 1e3,
                "status": jnp.asarray(_code("ok"))}


def test_summary_and_report_give_the_grid_in_the_files_units(tmp_path, monkeypatch):
    """A sweep file writes k in mm^3/(N m): summary.json's ``grid`` and the
    max's place are in that unit (5.05e-4, not 5.05e-13 1/Pa, and without
    the conversion's last-digit noise), ``grid_si`` keeps SI; the report
    says where the max is with units and names the output in words."""
    import dataclasses

    from diffwear.config import sweep as cfg

    monkeypatch.setitem(cfg.MODELS, "rig-wear",
                        dataclasses.replace(cfg.MODELS["rig-wear"], build=_Linear))
    f = tmp_path / "s.toml"
    f.write_text('model = "rig-wear"\n[grid]\nclearance = ["0.02 mm", "0.05 mm"]\n'
                 'k = ["5.05e-4 mm^3/(N m)", "1.01e-3 mm^3/(N m)"]\n')
    out = tmp_path / "out"
    assert main(["sweep", str(f), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["grid"]["k"] == {"unit": "mm^3/(N m)", "values": [5.05e-4, 1.01e-3]}
    assert summary["grid"]["clearance"] == {"unit": "mm", "values": [0.02, 0.05]}
    np.testing.assert_allclose(summary["grid_si"]["k_per_Pa"], [5.05e-13, 1.01e-12],
                               rtol=1e-15)
    top = summary["outputs"]["max_depth_mm"]
    assert top["argmax"] == {"clearance": 0.05, "k": 1.01e-3}
    assert top["max"] == pytest.approx(1.01e-3 * 0.05, rel=1e-12)
    report = (out / "report.md").read_text()
    assert "| max wear depth [mm] (`max_depth_mm`) |" in report
    assert "clearance = 0.05 mm, k = 0.00101 mm^3/(N m)" in report


def test_a_point_whose_run_ended_early_is_a_failed_point():
    """A run ended early (before its target: no answer) fails a point as a
    failed cycle model does; the wall reached and a contact warning carry an
    answer and do not; a NaN output fails it whatever its status.  The table
    holds the members' codes."""
    from diffwear.cli.sweep import failed_points, failure_words

    class Result:
        outputs = {"max_depth_mm": np.array([0.1, 0.2, 0.3, 0.4, np.nan, 0.6]),
                   "status": np.array([_code(n) for n in ("ok", "wall_reached",
                                                           "cycle_model_failed",
                                                           "run_ended_early", "ok",
                                                           "contact_lost")])}

        def __len__(self):
            return 6

    bad = failed_points(Result())
    assert bad.tolist() == [2, 3, 4]
    words = failure_words(Result(), bad)
    assert words == ("; cycle_model_failed: the cycle model failed (integrator or equilibrium "
                     "solve); run_ended_early: the run ended (steps or cycles) before the "
                     "wear limit or the requested cycles were reached")
