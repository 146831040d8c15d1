"""Pieces of the wear studies' reports shared by both wear models."""

from __future__ import annotations

import math

from ..report import Figure, Report, Table, render


def comparison_table(label: str, summary: dict, thesis: dict) -> Table:
    """Depth, volume and mass of the run beside each thesis model's (no thesis
    columns when ``thesis`` is empty)."""
    quantities = (("max wear depth [mm]", "max_wear_depth_mm", ".4f"),
                  ("wear volume [mm^3]", "wear_volume_mm3", ".2f"),
                  ("worn mass [g]", "worn_mass_g", ".4f"))
    return Table(("quantity", label, *thesis),
                 [(text, format(summary[key], fmt), *(v.get(key, "") for v in thesis.values()))
                  for text, key, fmt in quantities])


# What the comparison table's rows mean (every wear study's report gives it
# below the table).
COMPARISON_WORDS = ("max wear depth: the deepest point of the worn bushing profile; wear "
                    "volume: the material worn off the bushing (the profile integrated over "
                    "the bore and the bushing's depth); worn mass: that volume times the "
                    "bushing material's density.")


def peak_line(summary: dict) -> str:
    """Where the profile is deepest, in the bushing frame (a bullet item)."""
    angle = summary["max_wear_angle_rad"]
    return (f"peak wear at θ = {math.degrees(angle):.0f} deg ({angle:.3f} rad; bushing frame, "
            "from the rod axis crank->slider)")


def write_report(out, report: Report, figs, summary: dict) -> None:
    """report.md (``report``, then each figure) and summary.json into ``out``."""
    report = Report(report.title, [*report.blocks, *(Figure(f) for f in figs)])
    out.text("report.md", render(report))
    out.json("summary.json", summary)
