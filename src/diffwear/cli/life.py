"""``diffwear life two-joint``: the lives of one Ch. 8 design, and their Jacobian.

Writes ``summary.json``: ``cyc1``, ``cyc2`` (crank cycles until each joint's
peak wear depth reaches 2 mm), ``x_mm`` (d1, d2, h1, h2), ``model``, and with
``--jacobian`` a 2 x 4 ``jacobian`` (rows cyc1, cyc2; columns d1, d2, h1, h2;
cycles per mm) with its ``jacobian_method``: "autodiff" (jax.jacfwd) on the
quasi-static model, "finite-difference" (central, 1e-3 relative) on the
dynamic model, whose pointwise derivative at the limit is not the slope of its
life.  Also ``report.md``.
"""

from __future__ import annotations

import time

import numpy as np

from ..design.optimise import jacobian, jacobian_method, life_of
from ..design.two_joint import VARIABLES, TwoJointLife, check_design
from ..errors import InputError
from ..io import OutputDir
from ..models import Dynamic, QuasiStatic
from ..report import Block, Report, Table, render

NAME = "two-joint"
MODELS = ("quasi-static", "dynamic")


def model_for(name: str, *, n_theta: int = 90) -> TwoJointLife:
    """The Ch. 8 life model with the named wear model (default settings)."""
    if name not in MODELS:
        raise InputError(f"--model: unknown model {name!r}; choose from {', '.join(MODELS)}")
    wear_model = QuasiStatic() if name == "quasi-static" else Dynamic()
    return TwoJointLife(wear_model=wear_model, n_theta=n_theta).prepared()


def design_from_mm(values) -> np.ndarray:
    """(d1, d2, h1, h2) in mm -> m, checked against the Table 8-3 box (the
    error names the option)."""
    metres = []
    for name, v in zip(VARIABLES, values):
        if v is None:
            raise InputError(f"--{name} is required (mm)")
        metres.append(float(v) * 1e-3)
    x = np.asarray(metres)
    check_design(x, what="design (--d1 --d2 --h1 --h2)")
    return x


def run(out: OutputDir, x, *, model: str = "quasi-static", with_jacobian: bool = False,
        log=print) -> dict:
    life = model_for(model)
    t0 = time.perf_counter()
    cycles = life_of(life, x)
    summary = {"x_mm": (np.asarray(x) * 1e3).tolist(), "cyc1": float(cycles[0]),
               "cyc2": float(cycles[1]), "model": life.wear_model.name,
               "wear_limit_mm": life.limit * 1e3}
    if with_jacobian:
        jac = jacobian(life, x) * 1e-3
        summary["jacobian"] = jac.tolist()
        summary["jacobian_units"] = "cycles per mm; rows cyc1, cyc2; columns d1, d2, h1, h2"
        summary["jacobian_method"] = jacobian_method(life)
    summary["wall_time_s"] = time.perf_counter() - t0
    out.json("summary.json", summary)
    blocks: list[Block] = [Table(("d1 mm", "d2 mm", "h1 mm", "h2 mm", "cyc1", "cyc2"),
                                 [(*(f"{v:.3f}" for v in summary["x_mm"]),
                                   f"{summary['cyc1']:,.0f}", f"{summary['cyc2']:,.0f}")])]
    if with_jacobian:
        blocks += [f"Jacobian [cycles/mm] ({summary['jacobian_method']}):",
                   Table(("", "d1", "d2", "h1", "h2"),
                         [(f"cyc{i + 1}", *(f"{v:,.2f}" for v in row))
                          for i, row in enumerate(summary["jacobian"])])]
    out.text("report.md", render(Report(
        f"Lives of one two-joint design ({summary['model']} model)", blocks)))
    log(f"[life {NAME}] {summary['model']}: cyc1 {cycles[0]:,.0f}, cyc2 {cycles[1]:,.0f}")
    return summary
