"""The report renderer: blocks to markdown, exactly."""

import pytest

from diffwear.report import Bullets, Figure, Report, Section, Table, render


def test_render_writes_every_block_kind_once_in_order():
    report = Report("Run", [
        "One paragraph.",
        "",                                   # empty paragraphs are dropped
        Table(("joint", "F [N]"), [("crank|rod", 1.5), ("rod_slider", 2)], align="lr"),
        Section("Wear", [Bullets(["a", "b"]), Bullets([], strong=True),
                         Section("Detail", [Bullets(["stop"], strong=True)])]),
        Figure("wear.png"),
    ])
    assert render(report) == (
        "# Run\n\nOne paragraph.\n\n"
        "| joint | F [N] |\n|:---|---:|\n| crank\\|rod | 1.5 |\n| rod_slider | 2 |\n\n"
        "## Wear\n\n- a\n- b\n\n### Detail\n\n- **stop**\n\n"
        "![wear.png](wear.png)\n")


def test_tables_refuse_ragged_rows_and_bad_alignment():
    with pytest.raises(ValueError, match="rows \\[1\\]"):
        Table(("a", "b"), [(1, 2), (3,)])
    with pytest.raises(ValueError, match="align"):
        Table(("a", "b"), [(1, 2)], align="lc")
