"""Figures of diffwear's outputs, as PNG files, in the style of the thesis's
plots.  The matplotlib backend is the caller's choice: the ``diffwear``
command selects Agg (files only); a notebook keeps its inline backend.

`panels`: stacked time series, contact loci, wear profiles, a lubricated
joint's film over the cycle (shared);
`layout`: the rules they share (legends off the data, zero curves left out,
the bushing wall and the depth limit on depth axes); `references`: the
thesis's values beside a run (one open marker per kind, side by side, and a
strip of maxima); `files`: where a
figure becomes a file (`captured` reads the figures back, for tests);
`wear`: the wear studies; `pin_pivot`: the pin-pivot study; `design`: the
bushing design's life maps; `calibration`: the calibration's fits, residual
structure and candidate scores; `sweep`: grids (heatmaps, line plots),
tornado plots of elasticities, histograms of sampled outputs.
"""

from .files import captured
from .panels import film_panels, polar_loci, stacked, wear_panels, wear_title

__all__ = ["captured", "stacked", "polar_loci", "wear_panels", "wear_title", "film_panels"]
