"""Figures of diffwear's outputs, as PNG files, in the style of the thesis's
plots.  The matplotlib backend is the caller's choice: the ``diffwear``
command selects Agg (files only); a notebook keeps its inline backend.

`panels`: stacked time series, contact loci, wear profiles (shared);
`wear`: the wear studies; `pin_pivot`: the pin-pivot study; `design`: the
bushing design's life maps; `calibration`: the calibration's fits, residual
structure and candidate scores; `sweep`: grids (heatmaps, line plots),
tornado plots of elasticities, histograms of sampled outputs.
"""

from .panels import polar_loci, stacked, wear_panels

__all__ = ["stacked", "polar_loci", "wear_panels"]
