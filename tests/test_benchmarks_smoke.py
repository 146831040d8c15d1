"""The benchmark harness runs (quick mode, in-process) so that it cannot rot.

Only structure and positivity are checked, never timings.
"""

import json
import math
from pathlib import Path

import pytest

RUN_PY = Path(__file__).resolve().parents[1] / "benchmarks" / "run.py"
CASE = "ideal slider-crank, 2 s"


@pytest.fixture(scope="module")
def bench(load_benchmark):
    return load_benchmark("run")


def test_quick_run_writes_table_and_json(bench, tmp_path, capsys):
    target = tmp_path / "results" / "bench.json"
    assert bench.main(["--quick", "--json", str(target), "--case", CASE]) == 0
    table = capsys.readouterr().out
    assert table.startswith("| case |") and f"| {CASE} |" in table

    results = json.loads(target.read_text())
    assert results["meta"]["quick"] is True and results["meta"]["jax"]
    m = results["cases"][CASE]
    assert m["repeats"] == bench.QUICK_REPEATS == len(m["run_s_all"])
    assert m["simulated_s"] == 2.0
    assert m["integrator_steps"] > 0
    assert m["compile_s"] >= 0.0
    for key in ("run_s", "run_s_per_simulated_s"):
        assert math.isfinite(m[key]) and m[key] > 0.0, key
    assert all(t > 0.0 for t in m["run_s_all"])


def test_cases_registry_and_unknown_case(bench):
    assert CASE in bench.CASES and all(callable(f) for f in bench.CASES.values())
    with pytest.raises(KeyError, match="unknown benchmark case"):
        bench.run_cases(["no such case"], quick=True, log=lambda *a, **k: None)


CI_CASES = ("ideal slider-crank, 2 s", "clearance cycle, EFM c=0.5 mm", "scipy-peer")
# the whole-study cases (each a few minutes in quick mode): with --long
STUDY_CASES = ("ch8-optimisation", "calibration loop")


def _run_quick(tmp_path, cases):
    """`benchmarks/run.py --quick --case ...` as a user runs it (a subprocess):
    the table lists every case; returns the JSON's cases."""
    import subprocess
    import sys

    target = tmp_path / "bench.json"
    cmd = [sys.executable, str(RUN_PY), "--quick", "--json", str(target)]
    for case in cases:
        cmd += ["--case", case]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert all(f"| {c} |" in proc.stdout for c in cases)
    out = json.loads(target.read_text())["cases"]
    assert set(out) == set(cases)
    return out


@pytest.mark.extended
def test_quick_benchmark_subprocess_ci_cases(tmp_path):
    """The cheap cases in a subprocess: the JSON has its keys, the numbers are
    sane, and the SciPy peer (an independent NumPy implementation of the rig)
    agrees with diffwear on the joint force and the wear of a cycle."""
    cases = _run_quick(tmp_path, CI_CASES)
    for name in CI_CASES[:2]:
        m = cases[name]
        assert m["integrator_steps"] > 0 and m["compile_s"] >= 0.0, name
        assert math.isfinite(m["run_s"]) and m["run_s"] > 0.0, name

    peer = cases["scipy-peer"]
    for key in ("speedup_per_cycle", "ratio_rhs_scipy_to_diffwear", "diffwear_us_per_rhs",
                "scipy_us_per_rhs", "diffwear_us_per_step", "scipy_us_per_step"):
        assert math.isfinite(peer[key]) and peer[key] > 0.0, key
    # same start state (the peer derives it by hand from the geometry at phi1 = 0)
    assert peer["state_start_max_abs_diff"] < 1e-12
    # same model and tolerances: the step counts of two 5(4) pairs are close
    ratio = peer["scipy_steps_per_cycle"] / peer["diffwear_steps_per_cycle"]
    assert 0.7 < ratio < 1.4, ratio
    # agreement of the first wear cycle (measured: 2e-3, 1e-5, 1e-7)
    assert peer["force_max_rel_diff"] < 1e-2
    assert peer["force_mean_rel_diff"] < 1e-3
    assert peer["wear_increment_max_rel_diff"] < 1e-3
    assert peer["load_sliding_rel_diff"] < 1e-4
    # the rig's mean joint force: 90-170 N of spring force over the stroke
    # (presets: k_s (1.0 - x3 - L0) with x3 = 0.127..0.279 m)
    assert 90.0 < peer["mean_joint_force_N"] < 170.0


@pytest.mark.long
def test_quick_benchmark_subprocess_study_cases(tmp_path):
    """The design and calibration cases (whole studies) in quick mode."""
    cases = _run_quick(tmp_path, STUDY_CASES)
    cal = cases["calibration loop"]  # the shipped 21,400-cycle campaign, k and free length
    assert cal["dataset"] == "campaign-slow-run-in" and cal["parameters"] == 2
    # 4 x 360 profile points, 4 weighings, 72 force samples
    assert cal["points"] == 4 * 360 + 4 + 72
    for key in ("forward_s", "run_s", "ratio_gradient_to_forward"):
        assert math.isfinite(cal[key]) and cal[key] > 0.0, key

    ch8 = cases["ch8-optimisation"]
    assert isinstance(ch8["available"], bool)
    if not ch8["available"]:
        assert "not available" in ch8["note"]


def test_exudyn_peer_agrees(bench):
    """The Exudyn peer (benchmarks/peers/exudyn_slider_crank.py) against
    diffwear's ideal slider-crank; skipped where the ``bench`` extra is not
    installed (CI installs the test extra only)."""
    if bench.exudyn_python() is None:
        pytest.skip("exudyn is not installed (pip install -e \".[bench]\")")
    m = bench.exudyn_peer(bench.QUICK_REPEATS)
    assert m["available"] is True
    assert m["exudyn_step_s"] == bench.EXUDYN_STEP and m["exudyn_steps"] == 2000
    # measured at h = 1e-3: 1.4e-11 (both hold the position constraints),
    # 5e-5 of the 1,314 N peak, 1.6e-3 of the torque peak (generalized-alpha's
    # multipliers converge at first order in h)
    assert m["slider_x_max_diff_rel_stroke"] < 1e-8
    assert m["joint_force_max_rel_diff"] < 5e-4
    assert m["driver_torque_max_rel_diff"] < 5e-3
    assert abs(m["peak_joint_force_N"] - 1313.5) < 1.0
    for key in ("exudyn_solve_s", "exudyn_build_s", "diffwear_run_s", "ratio_exudyn_to_diffwear",
                "matched_run_s", "ratio_exudyn_to_diffwear_matched"):
        assert math.isfinite(m[key]) and m[key] > 0.0, key
    # matched accuracy: the post-stabilised route at rtol 1e-6 is within
    # Exudyn's joint-force error of the tight reference (measured: 1.2e-6
    # against 5.2e-5), so the matched route is at most that tolerance's cost
    routes = m["diffwear_routes"]
    exudyn_err = m["exudyn_joint_force_max_rel_diff_vs_reference"]
    assert routes["projection_rtol1e-06"]["joint_force_max_rel_diff"] < exudyn_err
    assert routes["projection_rtol1e-06"]["steps"] < 100 < routes["baumgarte_rtol1e-06"]["steps"]
    assert m["matched_route"] in routes and m["matched_steps"] < 100


def test_exudyn_peer_not_available(bench, monkeypatch, tmp_path):
    """Without an exudyn interpreter the case reports itself unavailable."""
    monkeypatch.setenv("DIFFWEAR_EXUDYN_PYTHON", str(tmp_path / "no-such-python"))
    assert bench.exudyn_python() is None
    m = bench.exudyn_peer(bench.QUICK_REPEATS)
    assert m == {"available": False, "note": m["note"]} and "not available" in m["note"]


@pytest.mark.long  # compiles the three batched models on the CPU: about three minutes
def test_the_prepared_gpu_script_runs_here_in_quick_mode(tmp_path, load_benchmark):
    """``benchmarks/gpu.py --quick`` on the CPU: every case runs, and the
    batched results are finite and counted (the GPU run is the same code)."""
    gpu = load_benchmark("gpu")
    target = tmp_path / "gpu.json"
    assert gpu.main(["--quick", "--json", str(target)]) == 0
    record = json.loads(target.read_text())
    cases = record["cases"]
    assert record["quick"] is True and record["backend"] == "cpu"
    assert cases["two_joint_lives"]["designs"] == 64 and cases["two_joint_lives"]["finite"]
    for name in ("qs_rig_sweep", "dynamic_rig_sweep"):
        assert cases[name]["points"] == (4 if name == "qs_rig_sweep" else 2)
        assert cases[name]["failed"] == 0 and cases[name]["points_per_s"] > 0
    assert cases["dynamic_rig_one"]["run_s"] > 0
