"""Calibration against measured data : effects, model, score test,
the whole loop on a small synthetic campaign, the CLI."""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.calibrate import load_dataset
from diffwear.calibrate.effects import (
    EFFECTS,
    NAMES,
    RUN_IN_CYCLES,
    ModifiedArchardWear,
    run_in_factor,
)
from diffwear.calibrate.fit import FitResult, ModelSettings, Problem
from diffwear.calibrate.identify import score_tests
from diffwear.calibrate.model import History, Observation, RigHistory, rig_defaults
from diffwear.calibrate.synthetic import Plan, synthesize
from diffwear.cli import main
from diffwear.mechanism import GuideFriction
from diffwear.wear import ArchardWear

ROOT = Path(__file__).resolve().parents[1]
SMALL_PLAN = Plan(cycles=1000.0, profile_cycles=(250.0, 500.0, 750.0, 1000.0),
                  volume_cycles=tuple(125.0 * i for i in range(1, 9)), force_cycles=(0.0,),
                  profile_angles=48, force_angles=48, holdout_from_cycles=750.0)
SMALL = ModelSettings(n_theta=60, force_samples=61)


# --------------------------------------------------------------- effects
def test_effects_at_zero_strength_are_the_base_law_bit_for_bit():
    p = jnp.array([0.0, 1e3, 3.7e5, 2.1e6])
    v = jnp.array([0.0, 0.01, 0.03, 0.2])
    k = 5.05e-13
    np.testing.assert_array_equal(ModifiedArchardWear(k).depth_rate(p, v),
                                  ArchardWear(k).depth_rate(p, v))
    assert float(run_in_factor(0.0, 250.0, 250.0)) == 1.0
    # d/d(exponent) at zero is finite at p = 0 (double where)
    g = jax.grad(lambda a: jnp.sum(ModifiedArchardWear(k, a).depth_rate(p, v)))(0.0)
    assert np.isfinite(g)


def test_modified_archard_closed_forms():
    p, v, k = 2.0e6, 0.05, 1e-13
    w = ModifiedArchardWear(k, exponent=0.5, pv_strength=2.0)
    expected = k * p * v * (p / 1e6) ** 0.5 * (1 + 2.0 * p * v / 1e5)
    assert float(w.depth_rate(p, v)) == pytest.approx(expected, rel=1e-13)


def test_run_in_factor_is_the_cycle_average():
    s, n0, span = 1.7, 300.0, 250.0
    n = np.linspace(n0, n0 + span, 200_001)
    mean = np.trapezoid(1 + s * np.exp(-n / RUN_IN_CYCLES), n) / span
    assert float(run_in_factor(s, n0, span)) == pytest.approx(mean, rel=1e-9)


def test_guide_friction_force():
    from diffwear.presets import rig_slider_crank

    mech, q = rig_slider_crank(extra_forces=(GuideFriction("g", "slider", 0.2, 83.0),))
    qd = jnp.zeros_like(q).at[3 * 2].set(0.05)  # slider moving +x at 5 cm/s
    frames = mech.frames(q, qd)
    f, _ = mech.element("g").forces(frames, jnp.zeros(0), 0.0)
    row = f[frames.row("slider")]
    np.testing.assert_allclose(row, [-0.2 * 83.0 * math.tanh(5.0), 0.0, 0.0], rtol=1e-12)


# --------------------------------------------------------------- observation
def _toy_history():
    theta = jnp.linspace(0, 2 * jnp.pi, 8, endpoint=False)
    wear = jnp.stack([jnp.zeros(8), jnp.arange(8.0), 2 * jnp.arange(8.0)]) * 1e-6
    return History(cycles=jnp.array([0.0, 100.0, 200.0]), wear=wear, creep=0.5 * wear,
                   force=jnp.stack([jnp.arange(9.0), 10 + jnp.arange(9.0)]),
                   crank_angle=jnp.linspace(0, 2 * jnp.pi, 9), theta=theta,
                   bushing_radius=jnp.asarray(0.01), bushing_depth=jnp.asarray(0.02),
                   ok=jnp.asarray(True))


def test_observations_interpolate_like_a_hand_calculation():
    h = _toy_history()
    # profile at N = 150 (halfway between snapshots 1 and 2), angle halfway between nodes 2 and 3
    prof = Observation("profile", np.array([2.5 * np.pi / 4]), 100.0, 2, cycles=150.0)(h)
    assert float(prof[0]) == pytest.approx(1.5 * 1.5 * 2.5e-6, rel=1e-12)  # (wear + creep)
    vol = Observation("volume", np.array([200.0]), 100.0, 2, basis="mass")(h)
    expected = 0.02 * 0.01 * (2 * np.pi / 8) * np.sum(2 * np.arange(8.0)) * 1e-6
    assert float(vol[0]) == pytest.approx(expected, rel=1e-12)
    vol_p = Observation("volume", np.array([200.0]), 100.0, 2, basis="profile")(h)
    assert float(vol_p[0]) == pytest.approx(1.5 * expected, rel=1e-12)
    # force of the cycle starting nearest N = 180 (cycle 1: 10, 11, ..., 18 at
    # 0, pi/4, ..., 2 pi); the first sample is dropped and the end one (18)
    # stands for angle 0, so pi/8 lies halfway between 18 and 11
    f = Observation("force", np.array([np.pi / 8, 0.0]), 100.0, 2, cycles=180.0)(h)
    np.testing.assert_allclose(f, [14.5, 18.0], rtol=1e-12)


# --------------------------------------------------------------- model
@pytest.fixture(scope="module")
def small_dataset(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cal") / "run_in"
    d = rig_defaults()
    synthesize(folder, name="small-run-in", effect="run_in", strength=2.0, seed=3,
               plan=SMALL_PLAN, settings=SMALL,
               truth={"k": 1.2 * d["k"], "free_length": d["free_length"] + 0.01})
    return folder


def test_zero_strength_model_equals_the_sweep_rig_model():
    """With every strength 0 (and the law's default contact band, as the sweep
    model) the calibration model is `sweep.RigWear`: same worn volume."""
    from diffwear.sweep.models import RigWear

    m = RigHistory(cycles=500.0, dynamic_cycles=2, n_theta=36, force_samples=37,
                   penetration_width=None)
    base = {k: jnp.asarray(v) for k, v in rig_defaults().items()}
    h = jax.jit(m)(base, jnp.zeros(len(NAMES)))
    assert bool(h.ok)
    vol = Observation("volume", np.array([500.0]), 250.0, 2)(h)
    rw = jax.jit(RigWear(cycles=500.0, dynamic_cycles=2, n_theta=36))(base)
    assert float(vol[0]) * 1e9 == pytest.approx(float(rw["volume_mm3"]), rel=1e-9)


def test_jacobian_of_wear_outputs_matches_central_differences(small_dataset):
    data = load_dataset(small_dataset)
    p = Problem.from_dataset(data, SMALL)
    wear_rows = np.isin(p.series_of_point,
                        [k for k, s in enumerate(data.series) if s.kind != "force"])
    x, s = jnp.zeros(p.n_base), jnp.zeros(len(NAMES)).at[0].set(1.0)
    res = jax.jit(lambda x, s: p.residual(x, s)[wear_rows])
    jx, js = jax.jit(jax.jacfwd(lambda x, s: p.residual(x, s)[wear_rows], argnums=(0, 1)))(x, s)
    eps = 1e-2  # the model's adaptive steps make smaller steps noisy
    for i in range(p.n_base):
        fd = (res(x.at[i].add(eps), s) - res(x.at[i].add(-eps), s)) / (2 * eps)
        assert float(jnp.linalg.norm(jx[:, i] - fd)) < 0.01 * float(jnp.linalg.norm(fd))
    for i in (NAMES.index("run_in"), NAMES.index("creep")):
        fd = (res(x, s.at[i].add(eps)) - res(x, s.at[i].add(-eps))) / (2 * eps)
        assert float(jnp.linalg.norm(js[:, i] - fd)) < 0.01 * float(jnp.linalg.norm(fd))


# --------------------------------------------------------------- score test
def test_score_statistic_is_the_chi2_drop_of_a_linear_model():
    rng = np.random.default_rng(0)
    n = 60
    jb = rng.normal(size=(n, 2))
    je = rng.normal(size=(n, len(EFFECTS)))
    truth = 0.7
    r_data = jb @ np.array([0.3, -0.2]) + je[:, 1] * truth + rng.normal(size=n)
    # base fit of the linear model r(x) = jb x - r_data
    xb, *_ = np.linalg.lstsq(jb, r_data, rcond=None)
    r = jb @ xb - r_data
    fitter = SimpleNamespace(problem=SimpleNamespace(holdout=np.zeros(n, bool)))
    base = FitResult(None, {}, {}, 0.0, 0.0, float(r @ r), n, 0.0, 0, r, r, 0, 0.0,
                     notes={"jacobian_base": jb, "jacobian_effects": je})
    scores = {s.effect: s for s in score_tests(fitter, base)}
    for k, eff in enumerate(EFFECTS):
        a = np.column_stack([jb, je[:, k]])
        z, *_ = np.linalg.lstsq(a, r_data, rcond=None)
        drop = float(r @ r - np.sum((a @ z - r_data) ** 2))
        if eff.lower >= 0 and z[-1] < 0:
            assert scores[eff.name].statistic == 0.0
        else:
            assert scores[eff.name].statistic == pytest.approx(drop, rel=1e-9)
            assert scores[eff.name].first_step == pytest.approx(z[-1], rel=1e-9)


# --------------------------------------------------------------- the loop
def test_calibrate_cli_identifies_run_in_on_a_small_campaign(small_dataset, tmp_path):
    out = tmp_path / "out"
    rc = main(["calibrate", str(small_dataset), "--out", str(out), "--n-theta", "60",
               "--top", "2", "--quiet"])
    assert rc == 0
    s = json.loads((out / "summary.json").read_text())
    for key in ("effect_identified", "effect_strength", "effect_strength_std",
                "heldout_rmse_before", "heldout_rmse_after", "candidates"):
        assert key in s
    assert s["effect_identified"] == "run_in"
    assert abs(s["effect_strength"] - 2.0) <= 2 * s["effect_strength_std"]
    assert s["heldout_rmse_before"] >= 3 * s["heldout_rmse_after"]
    assert s["candidates"][0]["name"] == "run_in"
    for f in ("report.md", "residuals.csv", "candidates.png", "residual_structure.png"):
        assert (out / f).is_file()
    # a second run refuses to overwrite the results
    before = (out / "summary.json").read_bytes()
    assert main(["calibrate", str(small_dataset), "--out", str(out), "--quiet"]) == 2
    assert (out / "summary.json").read_bytes() == before


@pytest.mark.parametrize("args, fragment", [
    (["calibrate", "no/such/folder", "--out", "X"], "no/such/folder"),
    (["calibrate", "design_studies/calibration/thesis_rig", "--out", "X", "--top", "0"], "--top"),
    (["calibrate", "design_studies/calibration/thesis_rig", "--out", "X", "--n-theta", "5"],
     "--n-theta"),
])
def test_calibrate_cli_bad_input(args, fragment, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(ROOT)
    args = [a if a != "X" else str(tmp_path / "out") for a in args]
    assert main(args) == 2
    assert fragment in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_calibrate_cli_help(capsys):
    with pytest.raises(SystemExit) as e:
        main(["calibrate", "--help"])
    assert e.value.code == 0
    assert "--out" in capsys.readouterr().out


SHIPPED = ROOT / "design_studies" / "calibration"


@pytest.mark.long  # the shipped campaigns take minutes each
@pytest.mark.parametrize("name", ["synthetic_run_in", "synthetic_pressure_exponent",
                                  "synthetic_creep", "synthetic_guide_friction",
                                  "synthetic_no_effect", "synthetic_outside_library"])
def test_shipped_campaigns(name, tmp_path):
    import importlib.util

    spec = importlib.util.spec_from_file_location("make", SHIPPED / "make_datasets.py")
    make = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(make)
    effect, strength, distort, _, _ = make.DATASETS[name]
    out = tmp_path / "out"
    assert main(["calibrate", str(SHIPPED / name), "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    if effect is None:
        assert s["effect_identified"] == "none"
        assert s["residual_unexplained"] == (distort is not None)
    else:
        assert s["effect_identified"] == effect
        assert abs(s["effect_strength"] - strength) <= 2 * s["effect_strength_std"]
        assert s["heldout_rmse_before"] >= 3 * s["heldout_rmse_after"]
