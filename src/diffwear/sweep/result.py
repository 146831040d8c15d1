"""`SweepResult`: named input and output columns of a sweep."""

from __future__ import annotations

import csv
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import InputError


@dataclass
class SweepResult:
    """Inputs (every parameter, swept or not) and outputs as flat NumPy columns
    in grid order (C order over ``grid_names``: the last varies fastest).

    ``grid_shape``: lengths of the grid arrays, in ``grid_names`` order;
    ``info``: how it was run (points, chunks, chunk size, padding, devices,
    ``order``: the evaluation order of the points, compile and run seconds).
    """

    inputs: dict[str, np.ndarray]
    outputs: dict[str, np.ndarray]
    grid_names: tuple[str, ...]
    grid_shape: tuple[int, ...]
    info: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return int(np.prod(self.grid_shape))

    @property
    def columns(self) -> dict[str, np.ndarray]:
        """Inputs then outputs (an output named like an input is an error at build time)."""
        return {**self.inputs, **self.outputs}

    def __getitem__(self, name: str) -> np.ndarray:
        cols = self.columns
        if name not in cols:
            raise KeyError(f"no column {name!r}; columns: {list(cols)}")
        return cols[name]

    def grid(self, name: str) -> np.ndarray:
        """Column ``name`` reshaped to the grid: array of shape ``grid_shape``."""
        return self[name].reshape(self.grid_shape)

    def axis(self, name: str) -> np.ndarray:
        """The grid values of the swept parameter ``name`` (its 1-D array)."""
        if name not in self.grid_names:
            raise KeyError(f"{name!r} is not a swept parameter; swept: {list(self.grid_names)}")
        i = self.grid_names.index(name)
        index: list[int | slice] = [0] * len(self.grid_shape)
        index[i] = slice(None)
        return self.grid(name)[tuple(index)]

    def table(self) -> list[dict[str, float]]:
        """One dict per grid point: every input and output as a Python float."""
        cols = self.columns
        return [{k: float(v[i]) for k, v in cols.items()} for i in range(len(self))]

    def to_csv(self, path) -> Path:
        """Write the table (header = column names, full float precision)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        cols = self.columns
        with path.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(list(cols))
            for row in zip(*cols.values()):
                w.writerow([repr(float(x)) for x in row])
        return path


def build_result(inputs, outputs, grid_names, grid_shape, info) -> SweepResult:
    clash = sorted(set(inputs) & set(outputs))
    if clash:
        raise InputError(f"sweep: model output(s) {clash} have the name of a parameter")
    return SweepResult(inputs, outputs, tuple(grid_names), tuple(grid_shape), info)
