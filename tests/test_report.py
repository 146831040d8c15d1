"""The report renderer: blocks to markdown, exactly."""

import pytest

from diffwear.report import (
    Bullets,
    Figure,
    PlusMinus,
    Report,
    Section,
    Significant,
    Table,
    Text,
    render,
)


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


def test_numbers_stay_numbers_until_the_report_is_rendered():
    """A `Text` of strings and numbers, in a paragraph, a bullet and a cell,
    reads as `significant` and `plus_minus` write them (hand-written here)."""
    chi2 = Text(("chi2 ", Significant(1463.04, 5), " on 1443 dof"))
    k = PlusMinus(6.0743e-13, 1.42e-15)
    report = Report("Fit", [
        chi2,
        Text(()),                                     # an empty text is dropped
        Bullets([Text(("k = ", k, " 1/Pa")), Text(("shape ", Significant(None, 3)))]),
        Table(("number", "value"), [("k", k), ("ratio", Text((Significant(0.000123456, 3),
                                                              "x")))]),
    ])
    # +- to the std's two digits, the value to the same decimal place (4 digits)
    assert render(report) == (
        "# Fit\n\nchi2 1463 on 1443 dof\n\n"
        "- k = 6.074e-13 +- 1.4e-15 1/Pa\n- shape n/a\n\n"
        "| number | value |\n|---|---|\n| k | 6.074e-13 +- 1.4e-15 |\n| ratio | 1.23e-04x |\n")


def test_tables_refuse_ragged_rows_and_bad_alignment():
    with pytest.raises(ValueError, match="rows \\[1\\]"):
        Table(("a", "b"), [(1, 2), (3,)])
    with pytest.raises(ValueError, match="align"):
        Table(("a", "b"), [(1, 2)], align="lc")


def test_a_run_reports_compiling_the_wear_model_that_ran():
    """The run report's compile time names the wear model that was compiled:
    none without wear, the quasi-static one when it ran (never "dynamic")."""
    from diffwear.cli.run import _compiled_wear

    assert _compiled_wear({}) == ""
    assert _compiled_wear({"joints": {"a": {"model": "quasi-static", "compile_time_s": 9.1}}}) \
        == " and the quasi-static wear model"
    assert _compiled_wear({"joints": {"a": {"model": "dynamic", "compile_time_s": 9.1},
                                      "b": {"model": "dynamic"}}}) \
        == " and the dynamic wear model"


def test_a_wear_studys_peak_is_given_in_degrees():
    """2.9670597 rad (the rig's grid point 85 of 180) is 170 deg."""
    from diffwear.studies._report import peak_line

    line = peak_line({"max_wear_angle_rad": 2 * 3.141592653589793 * 85 / 180})
    assert line.startswith("peak wear at θ = 170 deg (2.967 rad;")
