"""Calibration against measured wear data.

`load_dataset` reads a dataset folder (``dataset.toml`` plus CSV files, format
in the docs, "The dataset format") into a `Dataset` in SI units;
`write_dataset` writes one; `calibrate` runs the loop on it.
"""

from .dataset import (
    COLUMNS,
    KINDS,
    PARAMETERS,
    PRESETS,
    Dataset,
    Parameter,
    Series,
    load_dataset,
    write_dataset,
)
from .identify import calibrate

__all__ = ["COLUMNS", "KINDS", "PARAMETERS", "PRESETS", "Dataset", "Parameter", "Series",
           "load_dataset", "write_dataset", "calibrate"]
