"""The sweep's equality guarantees on a 16 x 16 (clearance, k) grid: the sweep
equals the single runs, and the sharded sweep equals the unsharded one.

The model is a cheap stand-in for the rig (one ODE, not the multibody wear
evolution, so that 256 single runs take seconds; the rig itself is checked on
a 2 x 2 grid in test_sweep.py): Archard wear of a pin in a PTFE bushing,

    dh/dt = k p v,   p = F / (2 L (b0(c) + sqrt(2 R h))),

a mean contact pressure p over a half-width that grows from the Hertz
line-contact half-width b0 (conformal radius R (R + c) / c) as the worn groove
of depth h widens; solved by diffrax (Tsit5, adaptive), so that batched
rounding could show up as it does in the real models.  Numbers: Table 7-1/7-2
rig (F ~ 139 N mean joint force, README; R 9.5 mm, L 13.1 mm, PTFE E 0.4 GPa
(Table 7-2), v = R omega at 30 rpm) over 2,000 s.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import jax
import numpy as np
import pytest

from diffwear.sweep import sweep

CHEAP = '''
import math
import diffrax, jax.numpy as jnp

F, R, L, E = 139.0, 9.5e-3, 13.1e-3, 0.4e9   # N, m, m, Pa (rig, Tables 7-1/7-2)
V = R * math.pi                              # m/s: pin surface speed at 30 rpm
T = 2000.0                                   # s of sliding

def cheap_wear(p):
    c, k = p["clearance"], p["k"]
    r_eff = R * (R + c) / c
    b0 = jnp.sqrt(4 * F * r_eff / (math.pi * L * E))
    rate = lambda t, h, a: k * V * F / (2 * L * (b0 + jnp.sqrt(2 * R * h + 1e-30)))
    sol = diffrax.diffeqsolve(diffrax.ODETerm(rate), diffrax.Tsit5(), 0.0, T, 1.0,
                              jnp.asarray(0.0),
                              stepsize_controller=diffrax.PIDController(rtol=1e-8, atol=1e-14),
                              max_steps=100_000)
    return {"max_depth_mm": sol.ys[-1] * 1e3, "steps": sol.stats["num_steps"].astype(float)}

BASE = {"clearance": 0.033e-3, "k": 5.05e-13}
GRID = {"clearance": list(__import__("numpy").geomspace(0.01e-3, 0.5e-3, 16)),
        "k": list(__import__("numpy").linspace(0.5, 1.5, 16) * 5.05e-13 * 1e3)}
'''
ns: dict = {}
exec(CHEAP, ns)
cheap_wear, BASE, GRID = ns["cheap_wear"], ns["BASE"], ns["GRID"]
SRC = Path(__file__).resolve().parents[1] / "src"


@pytest.fixture(scope="module")
def swept():
    return sweep(cheap_wear, BASE, GRID, chunk_size=48)  # 6 chunks, 32 padded slots


def test_16x16_sweep_equals_single_runs(swept):
    """Every one of the 256 points equals its single jitted run to 1e-12
    relative (and the same number of steps), in grid order."""
    assert swept.grid_shape == (16, 16) and swept.info["padding"] == 32
    one = jax.jit(cheap_wear)
    depth, steps = swept.grid("max_depth_mm"), swept.grid("steps")
    for i, c in enumerate(GRID["clearance"]):
        for j, k in enumerate(GRID["k"]):
            ref = one({"clearance": c, "k": k})
            assert swept.grid("clearance")[i, j] == c and swept.grid("k")[i, j] == k
            np.testing.assert_allclose(depth[i, j], float(ref["max_depth_mm"]), rtol=1e-12)
            assert steps[i, j] == float(ref["steps"])
    assert len(np.unique(steps)) > 3  # the adaptive cost differs over the grid


def test_cheap_model_against_scipy(swept):
    """Independent check of the stand-in itself at two corners (SciPy's LSODA)."""
    from scipy.integrate import solve_ivp

    F, R, L, E, V, T = (ns[n] for n in ("F", "R", "L", "E", "V", "T"))
    for i, j in ((0, 0), (15, 15)):
        c, k = GRID["clearance"][i], GRID["k"][j]
        b0 = np.sqrt(4 * F * R * (R + c) / c / (np.pi * L * E))
        sol = solve_ivp(lambda t, h: k * V * F / (2 * L * (b0 + np.sqrt(2 * R * max(h[0], 0)))),
                        (0, T), [0.0], method="LSODA", rtol=1e-10, atol=1e-16)
        np.testing.assert_allclose(swept.grid("max_depth_mm")[i, j], sol.y[0, -1] * 1e3,
                                   rtol=1e-6)


def test_16x16_sharded_equals_unsharded(swept):
    """The same grid over 4 forced host devices (shard_map, chunk 48 -> 48):
    equal to the single-device sweep to 1e-12, same steps."""
    code = CHEAP + '''
import json, jax
jax.config.update("jax_enable_x64", True)
from diffwear.sweep import sweep
assert jax.local_device_count() == 4
r = sweep(cheap_wear, BASE, GRID, chunk_size=48)
print(json.dumps({"devices": r.info["devices"], "d": r["max_depth_mm"].tolist(),
                  "s": r["steps"].tolist()}))
'''
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=4",
           "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]),
           "JAX_PLATFORMS": "cpu"}
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["devices"] == 4
    np.testing.assert_allclose(out["d"], swept["max_depth_mm"], rtol=1e-12, atol=0)
    np.testing.assert_array_equal(out["s"], swept["steps"])
