"""`sweep_distributed` on a local Dask cluster (2 worker processes) equals `sweep`.

Skipped when the ``cluster`` extra (dask[distributed]) is not installed; the
``test`` extra installs it, so CI runs it (~15 s: two worker processes each
import JAX and compile the toy model).
"""

import numpy as np
import pytest

from diffwear.errors import InputError
from diffwear.sweep import sweep

distributed = pytest.importorskip("distributed")

# The toy oscillator of test_sweep, defined by exec so that cloudpickle sends
# it to the workers by value (a test module is not importable there).
TOY = '''
import diffrax, jax.numpy as jnp

def toy(p):
    w, z = p["omega"], p["zeta"]
    f = lambda t, y, a: jnp.stack([y[1], -2 * z * w * y[1] - w ** 2 * y[0]])
    sol = diffrax.diffeqsolve(diffrax.ODETerm(f), diffrax.Tsit5(), 0.0, 1.0, 1e-3,
                              jnp.array([1.0, 0.0]) * p["x0"],
                              stepsize_controller=diffrax.PIDController(rtol=1e-8, atol=1e-8),
                              max_steps=100_000)
    # x1 - x0 * 1e-17: lost in float32 rounding, kept in float64
    return {"x1": sol.ys[-1, 0], "steps": sol.stats["num_steps"].astype(float),
            "tiny": (p["x0"] + 1e-12) - p["x0"]}
'''
ns: dict = {}
exec(TOY, ns)
toy = ns["toy"]
BASE = {"omega": 1.0, "zeta": 0.1, "x0": 2.0}
GRID = {"omega": [1.0, 10.0, 25.0, 40.0, 7.0], "zeta": [0.0, 0.05, 0.1]}


@pytest.fixture(scope="module")
def client():
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as c:
        yield c


@pytest.mark.slow
def test_distributed_equals_local(client):
    """15 points in tasks of 4 (the last 3) over 2 worker processes: every
    output equals the local sweep to 1e-10, in grid order, computed in float64
    on the workers; both workers took part."""
    from diffwear.sweep.distributed import sweep_distributed

    local = sweep(toy, BASE, GRID)
    dist = sweep_distributed(toy, BASE, GRID, client=client, points_per_task=4, chunk_size=3)
    assert dist.grid_shape == local.grid_shape == (5, 3)
    assert dist.info["tasks"] == 4 and dist.info["x64"]
    assert len(dist.info["workers"]) == 2
    for k in ("omega", "zeta", "x0"):
        np.testing.assert_array_equal(dist[k], local[k])
    np.testing.assert_allclose(dist["x1"], local["x1"], rtol=1e-10, atol=0)
    np.testing.assert_array_equal(dist["steps"], local["steps"])
    # float64 on the workers: 1e-12 survives (float32 would give 0 or ~2.4e-7)
    np.testing.assert_allclose(dist["tiny"], 1e-12, rtol=1e-3)
    # independent value: undamped oscillator, x(1) = x0 cos(omega)
    np.testing.assert_allclose(dist.grid("x1")[:, 0], 2.0 * np.cos(GRID["omega"]), rtol=1e-6)


@pytest.mark.slow
def test_distributed_default_split_and_bad_input(client):
    """Default: one task per worker; bad input is refused before anything is sent."""
    from diffwear.sweep.distributed import sweep_distributed

    r = sweep_distributed(toy, BASE, {"omega": [1.0, 2.0, 3.0]}, client=client)
    assert r.info["tasks"] == 2 and r.info["points_per_task"] == 2
    w, z = np.array([1.0, 2.0, 3.0]), 0.1
    wd = w * np.sqrt(1 - z ** 2)  # under-damped free response from rest, t = 1
    exact = 2.0 * np.exp(-z * w) * (np.cos(wd) + z / np.sqrt(1 - z ** 2) * np.sin(wd))
    np.testing.assert_allclose(r["x1"], exact, rtol=1e-6)
    with pytest.raises(InputError, match="'omegaa'"):
        sweep_distributed(toy, BASE, {"omegaa": [1.0]}, client=client)
    with pytest.raises(InputError, match="points_per_task"):
        sweep_distributed(toy, BASE, {"omega": [1.0]}, client=client, points_per_task=0)
