"""Calibration against measured wear data.

`load_dataset` reads a dataset folder (``dataset.toml`` plus CSV files, format
in the README, "Measured data and calibration") into a `Dataset` in SI units;
`write_dataset` writes one.
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

__all__ = ["COLUMNS", "KINDS", "PARAMETERS", "PRESETS", "Dataset", "Parameter", "Series",
           "load_dataset", "write_dataset"]
