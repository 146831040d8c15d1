"""Sweep files (``diffwear sweep FILE.toml``): a ready-made model, its static
settings, base values and grid axes, every dimensioned number with its unit.

    title = "..."                 optional
    model = "rig-wear"            | "clearance-force"
    [settings]                    static model settings (plain numbers / names)
    cycles = 21_400
    dynamic_cycles = 50
    n_theta = 180
    [base]                        fixed values; default: the model's defaults
    mu = 0.13
    [grid]                        one or more axes: a list, or a linspace table
    clearance = ["0.02 mm", "0.033 mm", "0.05 mm"]
    k = { start = "2.5e-4 mm^3/(N m)", stop = "1e-3 mm^3/(N m)", num = 4, spacing = "log" }
    [run]
    chunk_size = 8                points per vmap call on a GPU (default: all that fit)

A grid axis is a non-empty array of quantities (``"0.02 mm"``; plain numbers for
dimensionless parameters) or ``{ start, stop, num, spacing = "linear" | "log" }``.
Every value is checked against the parameter's range (e.g. clearance > 0).
Errors read ``FILE: KEY.PATH: what is wrong; allowed: ...`` as for mechanism
files.  `load_sweep` returns a `SweepSpec`; nothing runs here.
"""

from __future__ import annotations

import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import InputError
from ..models import QuasiStatic
from ..sweep.models import ClearanceForce, RigWear
from .schema import (
    Context,
    Field,
    Integer,
    Number,
    Quantity,
    Text,
    check_table,
    check_unknown,
    read_table,
    show,
    suggest,
    toml_type,
)

# Sanity bounds: beyond them a value is a typo, not a study.
MAX_POINTS = 100_000        # grid points of one sweep (each is a whole simulation)
MAX_AXIS = 10_000           # values of one axis
MAX_CYCLES = 100_000_000    # as the CLI's --cycles: ~6 years at 30 rpm


@dataclass(frozen=True)
class Param:
    """A sweepable parameter: its field (dimension and range) and how it is shown."""

    field: Field
    doc: str
    display_unit: str = ""      # unit for plots and tables; "" = dimensionless
    display_scale: float = 1.0  # SI value x scale = value in display_unit


def _length(doc, low=0.0):
    return Param(Quantity(dimension="length", low=low, low_open=True), doc, "mm", 1e3)


# Ranges: physical (positive lengths, 0 <= mu <= 1, 0 < e <= 1); none is a design limit.
RIG_PARAMS = {
    "k": Param(Quantity(dimension="wear coefficient", low=0.0, low_open=True),
               "Archard wear coefficient", "mm^3/(N m)", 1e9),
    "clearance": _length("radial clearance (bushing minus pin radius)"),
    "depth": _length("bushing depth (axial length)"),
    "diameter": _length("pin diameter"),
    "mu": Param(Number(low=0.0, high=1.0), "friction coefficient"),
    "free_length": _length("slider-spring free length"),
}
CLEARANCE_PARAMS = {
    "clearance": _length("radial clearance"),
    "mu": Param(Number(low=0.0, high=1.0), "friction coefficient"),
    "restitution": Param(Number(low=0.0, high=1.0, low_open=True), "coefficient of restitution"),
    "pin_radius": _length("pin radius"),
}

RIG_SETTINGS = {
    "cycles": Number(default=None, low=0.0, low_open=True, high=float(MAX_CYCLES)),
    "dynamic_cycles": Integer(default=None, low=1, high=100_000),
    "n_theta": Integer(default=None, low=8, high=3600),
    "force_samples": Integer(default=None, low=3, high=100_000),
    # the wear model: "dynamic" (default) or "quasi-static" (exact gradients, ms per point)
    "wear_model": Text(default=None, choices=("dynamic", "quasi-static")),
}
CLEARANCE_SETTINGS = {
    "law": Text(default=None, choices=("ln", "kv", "efm")),
    "cycles": Integer(default=None, low=1, high=1000),
    "transient_cycles": Integer(default=None, low=0, high=999),
    "samples_per_cycle": Integer(default=None, low=2, high=1_000_000),
    "n_theta": Integer(default=None, low=8, high=3600),
}


@dataclass(frozen=True)
class ModelSpec:
    build: Callable[..., Any]       # settings -> model function (with param_names, defaults)
    params: Mapping[str, Param]
    settings: Mapping[str, Field]
    description: str


def _rig(**kw):
    if "cycles" in kw:
        kw["cycles"] = float(kw["cycles"])
    if kw.get("wear_model") == "quasi-static":
        kw["wear_model"] = QuasiStatic()
    else:
        kw.pop("wear_model", None)
    return RigWear(**kw)


def _clearance(**kw):
    return ClearanceForce(**kw)


MODELS: dict[str, ModelSpec] = {
    "rig-wear": ModelSpec(_rig, RIG_PARAMS, RIG_SETTINGS,
                          "Ch. 7 rig bushing wear (sweep.models.RigWear)"),
    "clearance-force": ModelSpec(_clearance, CLEARANCE_PARAMS, CLEARANCE_SETTINGS,
                                 "Table 2-1 slider-crank clearance-joint force "
                                 "(sweep.models.ClearanceForce)"),
}
"""Model names of sweep files -> builder, parameters and settings."""

SECTIONS = ("title", "model", "settings", "base", "grid", "run")
LINSPACE = ("start", "stop", "num", "spacing")


@dataclass
class SweepSpec:
    file: str
    title: str
    model_name: str
    model: Any
    settings: dict
    base: dict[str, float]          # every parameter (SI), grid ones at their default
    grid: dict[str, np.ndarray]     # SI
    chunk_size: int | None
    params: Mapping[str, Param] = field(default_factory=dict)

    @property
    def points(self) -> int:
        return int(np.prod([a.size for a in self.grid.values()]))


def _axis(ctx: Context, path: str, raw, param: Param) -> np.ndarray:
    if isinstance(raw, dict):
        check_unknown(ctx, path, raw, LINSPACE)
        spec = read_table(ctx, path, raw, {
            "start": param.field, "stop": param.field,
            "num": Integer(low=1, high=MAX_AXIS),
            "spacing": Text(default="linear", choices=("linear", "log")),
        })
        fn = np.geomspace if spec["spacing"] == "log" else np.linspace
        if spec["num"] == 1 and spec["start"] != spec["stop"]:
            raise ctx.error(f"{path}.num", "num = 1 but start != stop",
                            "num >= 2, or start = stop")
        return fn(spec["start"], spec["stop"], spec["num"])
    if not isinstance(raw, list):
        raise ctx.error(path, f"expected an array of values or a {{start, stop, num}} table, "
                        f"got {toml_type(raw)} {show(raw)}",
                        f"e.g. [{_example(param)}, ...] or {{ start = {_example(param)}, "
                        f"stop = ..., num = 5 }}")
    if not raw:
        raise ctx.error(path, "the axis is empty", "one or more values")
    if len(raw) > MAX_AXIS:
        raise ctx.error(path, f"{len(raw)} values", f"at most {MAX_AXIS}")
    key = path.rsplit(".", 1)[-1]
    values = [param.field.read(ctx, f"{path}[{i}]", key, key, v) for i, v in enumerate(raw)]
    return np.asarray(values, dtype=float)


def _example(param: Param) -> str:
    if isinstance(param.field, Quantity):
        from .units import DIMENSIONS

        return repr(DIMENSIONS[param.field.dimension].example)
    return "0.1"


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and check a sweep file; `InputError` naming file and key for any problem."""
    path = Path(path)
    file = str(path)
    from .loader import decode, read_input

    data = read_input(path, "a path to a .toml sweep file")

    text = decode(data, file)
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise InputError(f"{file}: not valid TOML ({err})") from None
    return sweep_from_dict(raw, file=file)


def sweep_from_dict(raw: Mapping, *, file: str = "<sweep>") -> SweepSpec:
    ctx = Context(file)
    check_unknown(ctx, "", raw, SECTIONS)
    title = raw.get("title", "")
    if not isinstance(title, str):
        raise ctx.error("title", f"expected a string, got {toml_type(title)} {show(title)}")
    if "model" not in raw:
        raise ctx.error("model", "missing key", ", ".join(repr(m) for m in MODELS))
    name = raw["model"]
    if not isinstance(name, str) or name not in MODELS:
        what = (f"unknown model {name!r}{suggest(name, list(MODELS))}" if isinstance(name, str)
                else f"expected a string, got {toml_type(name)} {show(name)}")
        raise ctx.error("model", what, ", ".join(repr(m) for m in MODELS))
    spec = MODELS[name]

    settings_raw = check_table(ctx, "settings", raw.get("settings", {}), "static model settings")
    settings = {k: v for k, v in read_table(ctx, "settings", settings_raw, spec.settings).items()
                if v is not None}
    if name == "clearance-force" and "transient_cycles" in settings:
        cycles = settings.get("cycles", 2)
        if settings["transient_cycles"] >= cycles:
            raise ctx.error("settings.transient_cycles",
                            f"{settings['transient_cycles']} >= cycles = {cycles}",
                            f"0 <= transient_cycles < cycles ({cycles})")
    if name == "rig-wear":
        dyn = settings.get("dynamic_cycles", 50)
        cyc = settings.get("cycles", 21_400.0)
        if dyn > cyc:
            raise ctx.error("settings.dynamic_cycles", f"{dyn} > cycles = {cyc:g}",
                            "1 <= dynamic_cycles <= cycles (extrapolation factor >= 1)")
    model = spec.build(**settings)

    base_raw = check_table(ctx, "base", raw.get("base", {}), "parameter = value")
    fields = {k: p.field for k, p in spec.params.items()}
    check_unknown(ctx, "base", base_raw, list(spec.params),
                  hint=f" (parameters of model {name!r})")
    base = dict(model.defaults)
    for key in base_raw:
        base[key] = read_table(ctx, "base", {key: base_raw[key]}, {key: fields[key]})[key]

    if "grid" not in raw:
        raise ctx.error("grid", "missing section", "a [grid] table: parameter = [values]")
    grid_raw = check_table(ctx, "grid", raw["grid"], "parameter = [values]")
    if not grid_raw:
        raise ctx.error("grid", "no axis", f"one or more of {', '.join(spec.params)}")
    check_unknown(ctx, "grid", grid_raw, list(spec.params),
                  hint=f" (parameters of model {name!r})")
    grid = {}
    for key, value in grid_raw.items():
        if key in base_raw:
            raise ctx.error(f"grid.{key}", "also given in [base]", "a parameter in [base] or "
                            "[grid], not both")
        grid[key] = _axis(ctx, f"grid.{key}", value, spec.params[key])
    points = int(np.prod([a.size for a in grid.values()]))
    if points > MAX_POINTS:
        raise ctx.error("grid", f"{points} grid points", f"at most {MAX_POINTS}")

    run_raw = check_table(ctx, "run", raw.get("run", {}), "run options")
    run = read_table(ctx, "run", run_raw, {"chunk_size": Integer(default=None, low=1,
                                                                 high=MAX_POINTS)})
    return SweepSpec(file, title, name, model, settings, base, grid, run["chunk_size"],
                     spec.params)


__all__ = ["MODELS", "Param", "SweepSpec", "load_sweep", "sweep_from_dict"]
