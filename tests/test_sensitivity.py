"""Sensitivity (AD gradients, elasticities, tornado) and the propagation of the
wear-coefficient scatter.

Model: the cheap Archard stand-in of test_sweep_equality (one adaptive ODE,
rtol 1e-10 here so that AD and central differences can agree tightly; the rig
evolution's AD-FD gap at its tolerance 1e-6 is 1-4 %, see README), plus a
linear-in-k variant for the uncertainty check.
"""

import math

import numpy as np
import pytest

from diffwear.errors import InputError
from diffwear.plots.sweep import histogram, tornado
from diffwear.sweep.sensitivity import (
    finite_differences,
    moments,
    propagate_scatter,
    sample,
    sensitivity,
)

MODEL = '''
import math
import diffrax, jax.numpy as jnp

R, L, E, T = 9.5e-3, 13.1e-3, 0.4e9, 2000.0   # rig: pin radius, bushing depth, PTFE E, s

def wear(p, linear=False):
    c, k, F, V = p["clearance"], p["k"], p["force"], p["speed"]
    b0 = jnp.sqrt(4 * F * R * (R + c) / c / (math.pi * L * E))
    grow = 0.0 if linear else 1.0
    rate = lambda t, h, a: k * V * F / (2 * L * (b0 + grow * jnp.sqrt(2 * R * h + 1e-30)))
    sol = diffrax.diffeqsolve(diffrax.ODETerm(rate), diffrax.Tsit5(), 0.0, T, 1.0,
                              jnp.asarray(0.0),
                              stepsize_controller=diffrax.PIDController(rtol=1e-10, atol=1e-16),
                              max_steps=100_000)
    h = sol.ys[-1]
    return {"max_depth_mm": h * 1e3, "volume_mm3": 2 * b0 * L * h * 1e9 / 2}
'''
ns: dict = {}
exec(MODEL, ns)
wear = ns["wear"]
POINT = {"clearance": 0.033e-3, "k": 5.05e-13, "force": 139.0, "speed": 9.5e-3 * math.pi}


def linear_wear(p):
    return wear(p, linear=True)


@pytest.fixture(scope="module")
def sens():
    return sensitivity(wear, POINT)


def test_gradient_matches_central_differences(sens):
    """AD (jacfwd) equals central differences to 1e-5 relative for every output
    and parameter; the elasticity of the linear-in-k variant w.r.t. k and speed
    is exactly 1 and w.r.t. force 1/2 (depth = k V F T / (2 L b0), b0 ~ sqrt(F))."""
    fd = finite_differences(wear, POINT, rel_step=1e-5)
    for o in ("max_depth_mm", "volume_mm3"):
        for p in POINT:
            np.testing.assert_allclose(sens.gradient[o][p], fd.gradient[o][p], rtol=1e-5,
                                       err_msg=f"{o} / {p}")
    lin = sensitivity(linear_wear, POINT)
    assert lin.elasticity("max_depth_mm", "k") == pytest.approx(1.0, rel=1e-9)
    assert lin.elasticity("max_depth_mm", "speed") == pytest.approx(1.0, rel=1e-9)
    assert lin.elasticity("max_depth_mm", "force") == pytest.approx(0.5, rel=1e-9)
    # b0 ~ sqrt((R + c) / c): d ln h / d ln c = -1/2 d ln((R + c)/c) / d ln c = R / (2 (R + c))
    c, R = POINT["clearance"], ns["R"]
    assert lin.elasticity("max_depth_mm", "clearance") == pytest.approx(R / (2 * (R + c)),
                                                                        rel=1e-8)


def test_elasticities_table_and_tornado(sens, tmp_path):
    """The groove widening makes depth sub-linear in k (0 < e < 1); table rows
    and CSV agree with the elasticities; the tornado plot is a PNG."""
    e_k = sens.elasticity("max_depth_mm", "k")
    assert 0.3 < e_k < 1.0
    rows = sens.table()
    assert len(rows) == 2 * 4
    row = next(r for r in rows if r["output"] == "max_depth_mm" and r["parameter"] == "k")
    assert row["elasticity"] == e_k
    assert row["elasticity"] == pytest.approx(row["p"] * row["dy_dp"] / row["y"])
    text = sens.markdown()
    assert "| k |" in text and f"{e_k:+.3f}" in text
    sens.to_csv(tmp_path / "e.csv")
    assert (tmp_path / "e.csv").read_text().count("\n") == 9
    png = tornado(tmp_path / "t.png", sens, "max_depth_mm")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_samples_have_the_documented_spread():
    """Log-normal: 95 % of 20,000 samples within [k0/1.5, 1.5 k0] (to 0.5 %),
    median k0, mean/std as `moments`; uniform: within k0 (1 +- 0.5)."""
    ks = sample(1.0, 0.5, 20_000, seed=1)
    inside = np.mean((ks > 1 / 1.5) & (ks < 1.5))
    assert inside == pytest.approx(0.95, abs=0.005)
    assert np.median(ks) == pytest.approx(1.0, abs=0.01)
    m, s = moments(1.0, 0.5)
    assert np.mean(ks) == pytest.approx(m, rel=0.005) and np.std(ks) == pytest.approx(s, rel=0.02)
    u = sample(2.0, 0.5, 20_000, distribution="uniform", seed=1)
    assert u.min() >= 1.0 and u.max() <= 3.0
    assert np.std(u) == pytest.approx(moments(2.0, 0.5, "uniform")[1], rel=0.02)
    with pytest.raises(InputError, match="scatter"):
        sample(1.0, 1.5, 10, distribution="uniform")
    with pytest.raises(InputError, match="distribution"):
        sample(1.0, 0.5, 10, distribution="normal")


def test_scatter_propagation_linear_model(tmp_path):
    """Depth linear in k: the sampled mean and std equal the linear prediction
    (which is exact here) within sampling error (256 samples: 4 standard
    errors for the mean, 20 % for the std), and the life (cycles to reach
    0.5 mm) is cycles x limit / depth per sample."""
    prop = propagate_scatter(linear_wear, POINT, "k", scatter=0.5, n=256, seed=3,
                             chunk_size=128, life=("max_depth_mm", 0.5, 21_400))
    s = prop.stats["max_depth_mm"]
    y0 = prop.y0["max_depth_mm"]
    m, sd = moments(POINT["k"], 0.5)
    assert s["mean_linear"] == pytest.approx(y0 * m / POINT["k"], rel=1e-9)
    assert s["std_linear"] == pytest.approx(y0 * sd / POINT["k"], rel=1e-9)
    assert abs(s["mean"] - s["mean_linear"]) < 4 * s["std_linear"] / math.sqrt(256)
    assert s["std"] == pytest.approx(s["std_linear"], rel=0.2)
    # on the same samples the linear estimate is exact for a linear model
    assert s["mean"] == pytest.approx(s["mean_linear_samples"], rel=1e-9)
    assert s["std"] == pytest.approx(s["std_linear_samples"], rel=1e-9)
    np.testing.assert_allclose(prop.result["max_depth_mm"] / prop.result["k"], y0 / POINT["k"],
                               rtol=1e-9)  # exactly proportional per sample
    np.testing.assert_allclose(prop.life["samples"], 21_400 * 0.5 / prop.result["max_depth_mm"])
    assert prop.stats["life_cycles"]["p5"] < 21_400 * 0.5 / y0 < prop.stats["life_cycles"]["p95"]
    assert histogram(tmp_path / "h.png", prop, "max_depth_mm").read_bytes()[:4] == b"\x89PNG"
    assert histogram(tmp_path / "l.png", prop, "life_cycles").is_file()


def test_scatter_propagation_nonlinear_model():
    """Sub-linear depth (e_k < 1): the linearisation still gives the mean to
    ~1 % and the std to ~10 % at +-50 % scatter."""
    prop = propagate_scatter(wear, POINT, "k", scatter=0.5, n=128, seed=4, chunk_size=128)
    s = prop.stats["max_depth_mm"]
    assert s["mean"] == pytest.approx(s["mean_linear"], rel=0.02)
    assert s["std"] == pytest.approx(s["std_linear"], rel=0.2)
    assert s["p5"] < prop.y0["max_depth_mm"] < s["p95"]
    # concave (e_k < 1): the mean falls below the linear estimate on the same samples
    assert s["mean"] < s["mean_linear_samples"]
    assert s["mean"] == pytest.approx(s["mean_linear_samples"], rel=0.02)
