"""Registry of the named studies run by ``diffwear study NAME``."""

from __future__ import annotations

from . import clearance_sweep, ideal_slider_crank, pin_pivot, rig_21400, rig_lubricated, wear_5000

STUDIES = {m.NAME: m for m in (ideal_slider_crank, clearance_sweep, wear_5000, rig_21400,
                                rig_lubricated, pin_pivot)}

__all__ = ["STUDIES"]
