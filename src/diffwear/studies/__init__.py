"""Registry of the named studies run by ``diffwear study NAME``."""

from __future__ import annotations

from . import clearance_sweep, ideal_slider_crank

STUDIES = {m.NAME: m for m in (ideal_slider_crank, clearance_sweep)}

__all__ = ["STUDIES"]
