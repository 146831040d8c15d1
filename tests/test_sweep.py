"""Parameter sweeps (`diffwear.sweep`): grid, chunks, padding, sharding, errors.

Most tests use a toy model (a damped oscillator solved by diffrax with an
adaptive step: its cost grows with omega, like a stiff contact), compiled in ~2 s;
the ready-made models are checked on tiny reduced problems (marked slow).
"""

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import jax
import numpy as np
import pytest

from diffwear.errors import InputError
from diffwear.sweep import Auto, Batched, Looped, Pooled, SweepResult, sweep
from diffwear.wear.status import RESULTS, code

TOY = '''
import diffrax, jax.numpy as jnp

def toy(p):
    w, z = p["omega"], p["zeta"]
    f = lambda t, y, a: jnp.stack([y[1], -2 * z * w * y[1] - w ** 2 * y[0]])
    sol = diffrax.diffeqsolve(diffrax.ODETerm(f), diffrax.Tsit5(), 0.0, 1.0, 1e-3,
                              jnp.array([1.0, 0.0]) * p["x0"],
                              stepsize_controller=diffrax.PIDController(rtol=1e-8, atol=1e-8),
                              max_steps=100_000)
    return {"x1": sol.ys[-1, 0], "steps": sol.stats["num_steps"].astype(float)}

BASE = {"omega": 1.0, "zeta": 0.1, "x0": 2.0}
GRID = {"omega": [1.0, 10.0, 25.0, 40.0], "zeta": [0.0, 0.05, 0.1, 0.3]}
'''
ns: dict = {}
exec(TOY, ns)
toy, BASE, GRID = ns["toy"], ns["BASE"], ns["GRID"]
SRC = Path(__file__).resolve().parents[1] / "src"


@pytest.fixture(scope="module")
def full():
    return sweep(toy, BASE, GRID, execution=Batched())


@pytest.fixture(scope="module")
def looped():
    return sweep(toy, BASE, GRID)


def test_on_a_cpu_the_default_runs_one_point_after_another_exactly_as_single_runs(looped):
    """`Auto` on a CPU loops (the toy is too cheap for a pool to pay), and a
    looped point is the single jitted run's result, bit for bit."""
    assert looped.info["execution"] == "looped" and looped.info["processes"] == 1
    one = jax.jit(toy)
    for i, w in enumerate(GRID["omega"]):
        for j, z in enumerate(GRID["zeta"]):
            ref = one({"omega": w, "zeta": z, "x0": 2.0})
            assert looped.grid("x1")[i, j] == float(ref["x1"])
            assert looped.grid("steps")[i, j] == float(ref["steps"])


def test_matches_single_runs(full):
    """Every batched grid point equals a single jitted run of the model (rel 1e-10)."""
    one = jax.jit(toy)
    assert full.info["execution"] == "batched"
    assert full.grid_shape == (4, 4) and len(full) == 16
    for i, w in enumerate(GRID["omega"]):
        for j, z in enumerate(GRID["zeta"]):
            ref = one({"omega": w, "zeta": z, "x0": 2.0})
            np.testing.assert_allclose(full.grid("x1")[i, j], float(ref["x1"]), rtol=1e-10)
            assert full.grid("steps")[i, j] == float(ref["steps"])
            assert full.grid("omega")[i, j] == w and full.grid("zeta")[i, j] == z
    assert np.all(full["x0"] == 2.0)  # the base parameter is a column too
    np.testing.assert_array_equal(full.axis("zeta"), GRID["zeta"])
    assert full.grid("steps")[-1, 0] > 5 * full.grid("steps")[0, 0]  # cost varies


@pytest.mark.parametrize("chunk_size, order", [(5, False), (16, False), (3, True), (100, False)])
def test_chunked_and_ordered_equal_unchunked(full, chunk_size, order):
    """Chunks (with a padded last chunk) and cost ordering change nothing."""
    r = sweep(toy, BASE, GRID, chunk_size=chunk_size,
              order_by=(lambda p: p["omega"] * (1 - p["zeta"])) if order else None)
    size = min(chunk_size, 16)
    assert r.info["chunk_size"] == size
    assert r.info["chunks"] == -(-16 // size)
    assert r.info["padding"] == r.info["chunks"] * size - 16
    for k in ("x1", "steps", "omega", "zeta"):
        np.testing.assert_allclose(r[k], full[k], rtol=1e-10, atol=0, err_msg=k)


def test_a_sweep_too_big_for_memory_is_chunked_to_fit(full, monkeypatch):
    """With the memory available set to what 5 points need (XLA's own count
    of the 16-point program, per point), the default sweep runs in chunks of
    4 (half the memory: `MEMORY_SHARE`) with the same results; a requested
    chunk that does not fit is refused with the estimate, and so is a model
    of which one point does not."""
    from diffwear.sweep import memory

    per_point = full.info["bytes_per_point"]
    assert per_point > 0  # XLA gives the count on this backend
    monkeypatch.setattr(memory, "available_bytes", lambda device: 9.0 * per_point)
    r = sweep(toy, BASE, GRID, execution=Batched())
    assert r.info["chunk_size"] == 4 and r.info["chunks"] == 4
    for k in ("x1", "steps"):
        np.testing.assert_allclose(r[k], full[k], rtol=1e-10, atol=0, err_msg=k)
    too_big = r"chunk_size 8 needs ~.* GB .*allowed: chunk_size <= [1-7]$"
    with pytest.raises(InputError, match=too_big):
        sweep(toy, BASE, GRID, chunk_size=8)
    monkeypatch.setattr(memory, "available_bytes", lambda device: 1.0 * per_point)
    with pytest.raises(InputError, match="one point of this model needs"):
        sweep(toy, BASE, GRID, execution=Batched())


def _small_rig():
    """A ready-made model (it pickles, so a pool can take it): the quasi-static
    rig wear over 2,000 cycles on a 60-node profile."""
    from diffwear.models import QuasiStatic
    from diffwear.sweep.models import RigWear

    model = RigWear(cycles=2000.0, n_theta=60, wear_model=QuasiStatic())
    return model, {"clearance": np.linspace(0.2e-3, 0.4e-3, 5)}


def test_a_pool_of_processes_gives_the_loops_numbers_exactly():
    """Two worker processes running the program compiled here (sent to
    them, not compiled again) against the loop here: the same program, so
    the same bits; the progress callback counts every point once."""
    model, grid = _small_rig()
    seen = []
    pooled = sweep(model, model.defaults, grid, execution=Pooled(workers=2), progress=seen.append)
    loop = sweep(model, model.defaults, grid, execution=Looped())
    assert pooled.info["execution"] == "pooled" and pooled.info["processes"] == 2
    assert pooled.info["pool_program"] == "sent" and pooled.info["pool_compile_s"] < 1e-3
    assert loop.info["execution"] == "looped" and sum(seen) == 5
    for k in ("max_depth_mm", "volume_mm3", "mean_joint_force_N", "status"):
        np.testing.assert_array_equal(pooled[k], loop[k], err_msg=k)
    assert np.all(np.diff(loop["max_depth_mm"]) != 0)  # the points differ


_CACHED_POOL = """
import json, sys
import jax
import numpy as np
jax.config.update("jax_enable_x64", True)
jax.config.update("jax_compilation_cache_dir", sys.argv[1])
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
from diffwear.models import QuasiStatic
from diffwear.sweep import Pooled, sweep
from diffwear.sweep.models import RigWear

model = RigWear(cycles=2000.0, n_theta=60, wear_model=QuasiStatic())
grid = {"clearance": np.linspace(0.2e-3, 0.4e-3, 5)}
run = sweep(model, model.defaults, grid, execution=Pooled(workers=2))
print(json.dumps([run.info["execution"], run["max_depth_mm"].tolist()]))
"""


def test_a_pool_runs_a_program_the_compilation_cache_already_holds(tmp_path):
    """With JAX's persistent compilation cache on (as the command line has
    it), a second process's pooled sweep of the same model finds its
    program in the cache.  A CPU program loaded from there serialises
    without some of its kernels (the pool's processes would fail to run
    it), so the program sent to the pool is compiled afresh: both sweeps
    give the loop's numbers, bit for bit."""
    runs = []
    for _ in range(2):  # the first fills the cache, the second loads from it
        out = subprocess.run([sys.executable, "-c", _CACHED_POOL, str(tmp_path)],
                             capture_output=True, text=True, timeout=600)
        assert out.returncode == 0, out.stderr[-2000:]
        runs.append(json.loads(out.stdout.strip().splitlines()[-1]))
    assert any(tmp_path.iterdir())
    model, grid = _small_rig()
    loop = sweep(model, model.defaults, grid, execution=Looped())
    for execution, depth in runs:
        assert execution == "pooled"
        np.testing.assert_array_equal(depth, loop["max_depth_mm"])


def test_auto_moves_the_rest_to_a_pool_when_it_pays(monkeypatch):
    """`Auto` runs the first two points here (compile, then one timed), and
    the other three over the pool when `pool_pays` says so; a model that does
    not pickle (a lambda) goes too, as its compiled program."""
    from diffwear.sweep import runner

    model, grid = _small_rig()
    asked = []

    def pays(remaining, per_point_s, workers, compile_s=0.0):
        asked.append((remaining, workers, compile_s))
        return True

    monkeypatch.setattr(runner, "pool_pays", pays)
    auto = sweep(lambda p: model(p), model.defaults, grid, execution=Auto(workers=2))
    loop = sweep(model, model.defaults, grid, execution=Looped())
    assert asked == [(3, 2, 0.0)] and auto.info["execution"] == "pooled"  # program sent
    np.testing.assert_array_equal(auto["max_depth_mm"], loop["max_depth_mm"])


def test_auto_keeps_the_points_here_when_the_pool_cannot_take_the_model(monkeypatch):
    """Where the compiled program cannot be sent (here: made so), the pool
    compiles the model itself, which must then unpickle there: one whose
    module exists only in this process cannot.  `Auto` finishes the points in
    the loop and says why in the info; `Pooled` reports the failure, and a
    lambda is refused up front."""
    import types

    from diffwear.errors import SolverError
    from diffwear.sweep import runner

    module = types.ModuleType("diffwear_model_made_in_this_process")
    exec(TOY, module.__dict__)
    module.toy.__module__ = module.__name__
    monkeypatch.setitem(sys.modules, module.__name__, module)
    monkeypatch.setattr(runner, "pool_pays", lambda *args: True)
    monkeypatch.setattr(runner, "serialized", lambda compiled: None)
    grid = {"omega": [1.0, 10.0, 25.0, 40.0]}
    auto = sweep(module.toy, BASE, grid, execution=Auto(workers=2))
    assert auto.info["execution"] == "looped"
    assert "No module named 'diffwear_model_made_in_this_process'" in auto.info["pool_error"]
    np.testing.assert_array_equal(auto["x1"], sweep(toy, BASE, grid)["x1"])
    with pytest.raises(SolverError, match="could not start"):
        sweep(module.toy, BASE, grid, execution=Pooled(workers=2))
    with pytest.raises(InputError, match="cannot be pickled"):
        sweep(lambda p: toy(p), BASE, grid, execution=Pooled(workers=2))


@pytest.mark.extended
def test_a_program_with_python_callbacks_is_compiled_in_each_pool_process():
    """XLA cannot serialise a program that calls back into Python (the
    dynamic model's checks do); such a program is not sent, each process
    compiles the model itself, with the loop's results."""
    from diffwear.sweep.execution import compile_point, run_pool, serialized

    def with_callback(p):
        jax.debug.callback(lambda x: None, p["omega"])
        return toy(p)

    assert serialized(compile_point(with_callback, list(BASE))) is None
    model, grid = _small_rig()
    names = list(model.defaults)
    cols = {k: np.full(2, v) for k, v in model.defaults.items()}
    cols["clearance"] = grid["clearance"][:2]
    results = {k: np.full(2, np.nan) for k in ("max_depth_mm", "volume_mm3",
                                               "mean_joint_force_N", "status")}
    info = run_pool(None, model, cols, np.arange(2), 2, results)
    assert info["pool_program"] == "compiled in each process" and info["pool_compile_s"] > 0
    loop = sweep(model, model.defaults, {"clearance": grid["clearance"][:2]},
                 execution=Looped())
    np.testing.assert_array_equal(results["max_depth_mm"], loop["max_depth_mm"])
    assert names == list(cols)


def test_a_pool_pays_when_the_time_it_saves_exceeds_its_start_up():
    """Over w processes, n points of t seconds save n t (1 - 1/w); a pool
    costs `POOL_START_S`, and a compilation where the program cannot be
    sent."""
    from diffwear.sweep.execution import POOL_START_S, pool_pays

    assert pool_pays(10, 2.0, 2) is (10 * 2.0 * 0.5 > POOL_START_S)
    assert pool_pays(100, 2.0, 2)
    assert not pool_pays(3, 2.0, 2)        # 3 s saved
    assert not pool_pays(1000, 2.0, 1)     # one core: nothing to share
    assert pool_pays(40, 0.2, 4) is (40 * 0.2 * 0.75 > POOL_START_S)
    assert pool_pays(10, 2.0, 2, compile_s=1.0) is (10.0 > POOL_START_S + 1.0)
    assert not pool_pays(10, 2.0, 2, compile_s=10.0)


def test_execution_options_that_do_not_go_together_are_refused():
    model, grid = _small_rig()
    with pytest.raises(InputError, match="belong to batched execution, not Looped"):
        sweep(toy, BASE, GRID, execution=Looped(), chunk_size=4)
    with pytest.raises(InputError, match="give chunk_size and devices to Batched"):
        sweep(toy, BASE, GRID, execution=Batched(), chunk_size=4)
    with pytest.raises(InputError, match="allowed: Batched"):
        sweep(toy, BASE, GRID, execution="loop")
    with pytest.raises(InputError, match="workers must be a positive integer"):
        sweep(model, model.defaults, grid, execution=Pooled(workers=0))
    r = sweep(toy, BASE, GRID, chunk_size=8)  # a chunk size asks for batches
    assert r.info["execution"] == "batched" and r.info["chunk_size"] == 8


def test_a_point_that_fails_in_a_pool_is_reported_as_the_pools_failure():
    """A point the program cannot run (its parameters do not match the
    program's) fails in the worker; the sweep raises a `SolverError` that
    says so, instead of hanging or returning NaN."""
    from diffwear.errors import SolverError
    from diffwear.sweep.execution import compile_point, run_pool, serialized

    model, _ = _small_rig()
    program = serialized(compile_point(model, list(model.defaults)))
    assert program is not None
    cols = {"not_a_parameter": np.zeros(3)}
    results = {"max_depth_mm": np.full(3, np.nan)}
    with pytest.raises(SolverError, match="the sweep's pool failed: "):
        run_pool(program, model, cols, np.arange(3), 2, results)


def test_padding_dropped():
    """A 3-point sweep in chunks of 2: the padded slot (a copy of the last point)
    leaves no trace; results stay in grid order."""
    r = sweep(toy, BASE, {"omega": [40.0, 1.0, 10.0]}, chunk_size=2,
              order_by=lambda p: -p["omega"])
    assert r.info["padding"] == 1 and len(r["x1"]) == 3
    one = jax.jit(toy)
    for i, w in enumerate([40.0, 1.0, 10.0]):
        ref = float(one({**BASE, "omega": w})["x1"])
        np.testing.assert_allclose(r["x1"][i], ref, rtol=1e-10)


def test_table_csv_and_grid(full, tmp_path):
    rows = full.table()
    assert len(rows) == 16 and set(rows[0]) == {"omega", "zeta", "x0", "x1", "steps"}
    assert rows[1]["omega"] == 1.0 and rows[1]["zeta"] == 0.05  # last name varies fastest
    path = full.to_csv(tmp_path / "out" / "sweep.csv")
    with path.open() as fh:
        back = list(csv.DictReader(fh))
    assert len(back) == 16
    assert float(back[7]["x1"]) == rows[7]["x1"]  # full precision (repr)
    assert isinstance(full, SweepResult) and full.grid("x1").shape == (4, 4)


def test_sharded_equals_unsharded(full):
    """4 forced host devices (XLA_FLAGS set before jax is imported, in a child
    process): shard_map over the devices gives the parent's numbers."""
    code = TOY + '''
import json, sys, jax
jax.config.update("jax_enable_x64", True)
from diffwear.sweep import sweep
assert jax.local_device_count() == 4, jax.local_devices()
r = sweep(toy, BASE, GRID, chunk_size=6)
print(json.dumps({"info": {k: r.info[k] for k in ("devices", "chunk_size", "chunks")},
                  "x1": r["x1"].tolist(), "steps": r["steps"].tolist()}))
'''
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=4",
           "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]),
           "JAX_PLATFORMS": "cpu"}
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                          text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert out["info"] == {"devices": 4, "chunk_size": 8, "chunks": 2}  # 6 -> multiple of 4
    np.testing.assert_allclose(out["x1"], full["x1"], rtol=1e-10, atol=0)
    np.testing.assert_array_equal(out["steps"], full["steps"])


@pytest.mark.parametrize("base, grid, match", [
    (BASE, {"omegaa": [1.0]}, "'omegaa'"),
    (BASE, {}, "grid is empty"),
    (BASE, {"omega": [[1.0, 2.0]]}, "'omega'.*1-D"),
    (BASE, {"zeta": [0.1, float("nan")]}, "'zeta'.*finite"),
    (BASE, {"zeta": []}, "'zeta'.*empty"),
    ({**BASE, "x0": float("inf")}, {"zeta": [0.1]}, "'x0'.*finite"),
    ({**BASE, "x0": [1.0, 2.0]}, {"zeta": [0.1]}, "'x0'.*scalar"),
])
def test_bad_input(base, grid, match):
    with pytest.raises(InputError, match=match):
        sweep(toy, base, grid)


def test_bad_input_against_model_names():
    from diffwear.sweep.models import ClearanceForce

    m = ClearanceForce()
    with pytest.raises(InputError, match="'clearence'"):
        sweep(m, m.defaults, {"clearence": [1e-3]})
    with pytest.raises(InputError, match="'pin'"):
        sweep(m, {**m.defaults, "pin": 1.0}, {"mu": [0.1]})
    with pytest.raises(InputError, match="'mu'"):
        sweep(m, {k: v for k, v in m.defaults.items() if k != "mu"}, {"clearance": [1e-3]})
    with pytest.raises(InputError, match="chunk_size"):
        sweep(toy, BASE, GRID, chunk_size=0)


@pytest.mark.slow
def test_rig_wear_sweep_matches_single_runs():
    """Reduced rig wear (n_theta 36, k x 100, 4 cycles = warm-up + 2 dynamic
    cycles at A = 2): a 2x2 (clearance, k) sweep equals single runs.

    Not to 1e-10: batched (vmapped) linear algebra rounds differently from the
    unbatched kernels (ulp level in the vector field), and the adaptive cycle
    integration (rtol 1e-6) turns that into a different step sequence; seen:
    7e-7 relative in the max depth, 1.3e-4 in the mean joint force (contact
    forces sampled at 37 times).  Hence rel 1e-5 and 1e-3."""
    from diffwear.sweep.models import RigWear

    m = RigWear(cycles=4.0, dynamic_cycles=2, n_theta=36, force_samples=37)
    base = {**m.defaults, "k": m.defaults["k"] * 100}
    grid = {"clearance": [0.02e-3, 0.05e-3], "k": [base["k"], 2 * base["k"]]}
    r = sweep(m, base, grid, chunk_size=3)
    one = jax.jit(m)
    for row in r.table():
        ref = one({k: row[k] for k in m.param_names})
        for key, rtol in (("max_depth_mm", 1e-5), ("volume_mm3", 1e-5),
                          ("mean_joint_force_N", 1e-3), ("status", 0)):
            np.testing.assert_allclose(row[key], float(ref[key]), rtol=rtol, err_msg=key)
    assert np.all(r["status"] == code(RESULTS.ok)) and np.all(r["volume_mm3"] > 0)
    v = r.grid("volume_mm3")
    np.testing.assert_allclose(v[:, 1] / v[:, 0], 2.0, rtol=0.05)  # Archard: V ~ k
    assert np.all(r["max_depth_mm"] <= r["max_depth_mm"].max())


@pytest.mark.slow
def test_clearance_force_sweep_matches_single_runs():
    """As for the rig (batched rounding -> another adaptive step sequence at
    rtol 1e-6), and the impact peaks, sampled at 50 saved times, amplify it:
    seen 3e-4 relative in the RMS force, 1.3 % in the peak force and 2 % in the
    step count at c = 0.1 mm."""
    from diffwear.sweep.models import ClearanceForce

    m = ClearanceForce(law="kv", cycles=1, transient_cycles=0, samples_per_cycle=50)
    r = sweep(m, m.defaults, {"clearance": [0.1e-3, 1e-3]})
    one = jax.jit(m)
    for row in r.table():
        ref = one({k: row[k] for k in m.param_names})
        for key, rtol in (("peak_force_N", 0.05), ("rms_force_N", 2e-3),
                          ("integrator_steps", 0.05)):
            np.testing.assert_allclose(row[key], float(ref[key]), rtol=rtol, err_msg=key)
    assert np.all(r["peak_force_N"] >= r["rms_force_N"])
