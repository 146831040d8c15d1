import jax
import pytest

jax.config.update("jax_enable_x64", True)

import diffwear  # noqa: E402,F401


def pytest_addoption(parser):
    parser.addoption("--long", action="store_true",
                     help="also run the tests marked slow or long (study reproductions, "
                          "notebooks, tight-tolerance gradient checks: minutes each)")


def pytest_collection_modifyitems(config, items):
    if config.getoption("--long"):
        return
    skip = pytest.mark.skip(reason="slow: runs with pytest --long")
    for item in items:
        if "long" in item.keywords or "slow" in item.keywords:
            item.add_marker(skip)
