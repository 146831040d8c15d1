"""Input checks and the full grid (cartesian product) of a sweep."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from ..errors import InputError


def _scalar(name: str, value) -> float:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"sweep: base parameter {name!r} must be a real number, "
                         f"got {value!r}") from None
    if arr.ndim != 0:
        raise InputError(f"sweep: base parameter {name!r} must be a scalar, got shape {arr.shape}")
    if not math.isfinite(float(arr)):
        raise InputError(f"sweep: base parameter {name!r} must be finite, got {float(arr)}")
    return float(arr)


def validate(base_params: Mapping, grid: Mapping, known=None):
    """Checked (base: name -> float, grid: name -> 1-D float64 array).

    ``known``: the model's parameter names (if it declares them); every base and
    grid name must be one of them.  Raises `InputError` naming the parameter.
    """
    if not isinstance(base_params, Mapping):
        raise InputError(f"sweep: base_params must be a dict name -> number, got "
                         f"{type(base_params).__name__}")
    if not isinstance(grid, Mapping) or len(grid) == 0:
        raise InputError("sweep: the grid is empty; give at least one parameter "
                         "name -> 1-D array of values")
    base = {}
    for name, value in base_params.items():
        if not isinstance(name, str):
            raise InputError(f"sweep: parameter names must be strings, got {name!r}")
        if known is not None and name not in known:
            raise InputError(f"sweep: unknown parameter {name!r} in base_params; the model "
                             f"takes {sorted(known)}")
        base[name] = _scalar(name, value)
    if known is not None:
        missing = [n for n in known if n not in base and n not in grid]
        if missing:
            raise InputError(f"sweep: parameter(s) {missing} have no value; give them in "
                             "base_params or grid")
    axes = {}
    for name, values in grid.items():
        if name not in base and (known is None or name not in known):
            allowed = sorted(base) if known is None else sorted(known)
            raise InputError(f"sweep: unknown parameter {name!r} in grid; the parameters "
                             f"are {allowed}")
        try:
            arr = np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"sweep: grid values of {name!r} must be real numbers") from None
        if arr.ndim != 1:
            raise InputError(f"sweep: grid values of {name!r} must be a 1-D array, "
                             f"got shape {arr.shape}")
        if arr.size == 0:
            raise InputError(f"sweep: grid values of {name!r} are empty")
        bad = ~np.isfinite(arr)
        if bad.any():
            raise InputError(f"sweep: grid values of {name!r} must be finite; entry "
                             f"{int(np.argmax(bad))} is {arr[bad][0]}")
        axes[name] = arr
    return base, axes


def full_grid(base: dict, axes: dict) -> tuple[dict, tuple[int, ...]]:
    """Every parameter as a flat column over the grid (C order: the last grid
    name varies fastest), and the grid shape."""
    shape = tuple(a.size for a in axes.values())
    mesh = np.meshgrid(*axes.values(), indexing="ij") if axes else []
    n = int(np.prod(shape)) if shape else 1
    cols = {name: np.full(n, value) for name, value in base.items()}
    for name, m in zip(axes, mesh):
        cols[name] = m.reshape(-1).copy()
    return cols, shape
