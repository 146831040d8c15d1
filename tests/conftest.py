import importlib.util
import os
import signal
import tempfile
from pathlib import Path

import jax
import pytest

jax.config.update("jax_enable_x64", True)
# The interrupt tests send SIGINT as a terminal's Ctrl-C would; a suite started
# with SIGINT ignored (nohup, a background job) is put back to Python's default.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)

import diffwear  # noqa: E402,F401

# The commands keep their compiled programs on disk (diffwear.cli.command):
# for the suite, in a folder of its own, not the user's cache.
os.environ.setdefault("DIFFWEAR_COMPILATION_CACHE",
                      tempfile.mkdtemp(prefix="diffwear-test-compilation-cache-"))


def pytest_addoption(parser):
    parser.addoption("--long", action="store_true",
                     help="also run the tests marked slow, long or extended (study "
                          "reproductions, notebooks, tight-tolerance gradient checks: "
                          "minutes each)")
    parser.addoption("--extended", action="store_true",
                     help="also run the tests marked extended (whole calibrations, dynamic "
                          "wear of mechanism files, worker processes: half a minute to a "
                          "minute each on 2 cores); CI runs them after the default run")


def pytest_configure(config):
    """Hypothesis profiles of the input fuzzing (tests/test_fuzz_inputs.py):
    ``short`` in the default run (200 examples a surface, about 20 s for all
    seven on 2 cores; derandomised: the same examples every run, so a failure
    reproduces), ``long`` under --long (25,000 random examples a surface,
    measured on a loaded 2-core machine: 3 to 16 min for each file surface,
    under a minute for each API one, 51 min for all; failures kept in the
    example database to replay); ``medium`` (400) by name,
    ``--hypothesis-profile=medium``."""
    from hypothesis import HealthCheck, settings

    common = dict(deadline=None, print_blob=True,
                  suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                         HealthCheck.function_scoped_fixture])
    settings.register_profile("short", max_examples=200, derandomize=True, database=None,
                              **common)
    settings.register_profile("long", max_examples=25_000, **common)
    settings.register_profile("medium", max_examples=400, **common)
    if not config.getoption("hypothesis_profile", None):  # one named on the command line wins
        settings.load_profile("long" if config.getoption("--long") else "short")


def pytest_collection_modifyitems(config, items):
    """Three tiers: the default run (the README's test command, <= 15 min on
    2 cores), ``--extended`` (CI adds it) and ``--long`` (everything)."""
    if config.getoption("--long"):
        return
    slow = pytest.mark.skip(reason="slow: runs with pytest --long")
    extended = pytest.mark.skip(reason="extended: runs with pytest --extended (CI) or --long")
    run_extended = config.getoption("--extended")
    for item in items:
        if "long" in item.keywords or "slow" in item.keywords:
            item.add_marker(slow)
        elif "extended" in item.keywords and not run_extended:
            item.add_marker(extended)


BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture(scope="session")
def load_benchmark():
    """``load_benchmark(name)``: the script ``benchmarks/NAME.py`` (not a
    package) loaded as a module."""
    def load(name: str):
        spec = importlib.util.spec_from_file_location(f"diffwear_benchmarks_{name}",
                                                      BENCHMARKS / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    return load
