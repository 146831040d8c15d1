"""The benchmark harness runs (quick mode, in-process) so that it cannot rot.

Only structure and positivity are checked, never timings.
"""

import importlib.util
import json
import math
from pathlib import Path

import pytest

RUN_PY = Path(__file__).resolve().parents[1] / "benchmarks" / "run.py"
CASE = "ideal slider-crank, 2 s"


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("diffwear_benchmarks_run", RUN_PY)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


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
