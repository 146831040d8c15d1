"""Pieces of the wear studies' reports shared by both wear models."""

from __future__ import annotations


def comparison_table(label: str, summary: dict, thesis: dict) -> list[str]:
    """The report's table: depth, volume and mass of the run beside each thesis
    model's (no thesis columns when ``thesis`` is empty)."""
    def row(*cells):
        return "| " + " | ".join(str(c) for c in cells) + " |"

    quantities = (("max wear depth [mm]", "max_wear_depth_mm", ".4f"),
                  ("wear volume [mm^3]", "wear_volume_mm3", ".2f"),
                  ("worn mass [g]", "worn_mass_g", ".4f"))
    return [row("quantity", label, *thesis), "|---" * (2 + len(thesis)) + "|",
            *(row(text, format(summary[key], fmt), *(v.get(key, "") for v in thesis.values()))
              for text, key, fmt in quantities)]


def peak_line(summary: dict) -> str:
    """Where the profile is deepest, in the bushing frame."""
    return (f"- peak wear at theta = {summary['max_wear_angle_rad']:.3f} rad (bushing frame, "
            "from the rod axis crank->slider)")


def write_report(out, rows: list[str], figs, summary: dict) -> None:
    """report.md (``rows``, then each figure) and summary.json into ``out``."""
    out.text("report.md", "\n".join([*rows, *(f"![{f}]({f})\n" for f in figs)]))
    out.json("summary.json", summary)

