"""``diffwear calibrate DATA_DIR --out DIR``: the measured-data loop
(`calibrate.identify.calibrate`) and its files (`calibrate.outputs.write`:
``summary.json``, ``residuals.csv``, the figures and ``report.md``).
"""

from __future__ import annotations

from ..calibrate.dataset import Dataset
from ..calibrate.fit import ModelSettings
from ..calibrate.forecast import DEFAULT_OUTLOOK
from ..calibrate.identify import calibrate
from ..calibrate.outputs import write
from ..io import OutputDir

DESCRIPTION = "calibrate the rig model on measured wear data and identify a missing effect"


def run(data: Dataset, out: OutputDir, *, settings: ModelSettings | None = None,
        top: int = 3, check: bool = True, discrepancy=None, outlook=DEFAULT_OUTLOOK,
        log=print) -> dict:
    """The loop on a loaded dataset (`load_dataset`: bad input is found before
    ``out`` exists), writing the files `calibrate.outputs` lists."""
    c = calibrate(data, settings, top=top, check=check, discrepancy=discrepancy,
                  outlook=outlook, log=log)
    return write(c, out, log)
