"""``diffwear sweep FILE.toml``: run a checked `SweepSpec` and write its outputs.

Outputs in the results folder (`io.OutputDir`: never over earlier results):

    results.csv     one row per grid point (grid order, last axis fastest): every
                    parameter in SI with its unit in the name (clearance_m,
                    k_per_Pa, mu), then every output (named with its unit)
    results.npz     the same columns, plus axis_<name> (SI) and grid_shape
    results.nc      NetCDF-3 (dimensions = grid axes), only if SciPy is
                    installed (extra ``diffwear[netcdf]``); skipped otherwise
    <output>.png    heatmap over a 2-D grid, line plot over a 1-D grid (none for
                    3-D and more: use the tables)
    summary.json    settings, axes (``grid``: in the units the tables and plots
                    show, e.g. k in mm^3/(N m); ``grid_si``: in SI), per-output
                    min/max and where (in ``grid``'s units), failed points,
                    timing (written last: marks a finished run)
    report.md       what was run and what came out, linking the rest
    input.toml      copy of the sweep file

A point failed if an output is not finite or its ``status`` (rig wear: the
code of a `diffwear.wear.RESULTS` member) says there is no answer
(`diffwear.wear.not_computed`: the cycle model failed, the run ended
early).  Failed points stay in the tables (NaN / status); the run then ends
with `SolverError` (CLI exit 3) after writing everything.
"""

from __future__ import annotations

import math
import time
from typing import Any

import jax
import numpy as np
from tqdm.auto import tqdm

from ..choices import SWEEP_DEVICES
from ..config.sweep import SweepSpec
from ..config.units import DIMENSIONS, key_suffix
from ..errors import InputError, SolverError
from ..io import OutputDir
from ..plots import sweep as plots_sweep
from ..report import Block, Figure, Report, Table, render
from ..sweep.execution import Auto, Batched
from ..sweep.result import SweepResult
from ..sweep.runner import sweep
from ..wear.status import from_code, members, message, name, not_computed

SKIP_PLOTS = ("status",)


def column_name(spec: SweepSpec, name: str) -> str:
    """``clearance`` -> ``clearance_m``: an input column named with its SI unit."""
    field = spec.params[name].field
    dim = getattr(field, "dimension", None)
    return name if dim is None else f"{name}_{key_suffix(DIMENSIONS[dim].si)}"


def label(spec: SweepSpec, name: str) -> str:
    p = spec.params[name]
    return f"{name} [{p.display_unit}]" if p.display_unit else name


def shown(spec: SweepSpec, name: str, values):
    return np.asarray(values, dtype=float) * spec.params[name].display_scale


def shown_value(spec: SweepSpec, name: str, value) -> float:
    """One value of axis ``name`` in its shown unit, to 12 significant digits
    (the unit conversion's last-digit noise, e.g. 0.0005050000000000001, cut)."""
    return float(f"{float(shown(spec, name, value)):.12g}")


def with_unit(spec: SweepSpec, name: str, value) -> str:
    """"k = 0.0005252 mm^3/(N m)": a grid value in its shown unit, 4 digits."""
    unit = spec.params[name].display_unit
    return f"{name} = {float(shown(spec, name, value)):.4g}" + (f" {unit}" if unit else "")


def failed_points(res: SweepResult) -> np.ndarray:
    bad = np.zeros(len(res), dtype=bool)
    for col in res.outputs.values():
        bad |= ~np.isfinite(col)
    if "status" in res.outputs:  # no answer: the model failed or ran out of steps
        bad |= np.asarray(not_computed(_statuses(res)))
    return np.flatnonzero(bad)


def _statuses(res: SweepResult):
    """The points' `RESULTS` from their ``status`` codes (a NaN code, a point
    that raised, read as ok: its NaN outputs fail it already)."""
    codes = np.asarray(res.outputs["status"], dtype=float)
    return from_code(np.where(np.isfinite(codes), codes, 0.0))


def failure_words(res: SweepResult, bad: np.ndarray) -> str:
    """'; cycle_model_failed: why' for each status without an answer among
    the points ``bad``."""
    if "status" not in res.outputs or not bad.size:
        return ""
    status = _statuses(res)
    return "".join(f"; {name(m)}: {message(m)}" for m in members()
                   if bool(not_computed(m)) and bool(np.any(np.asarray(status == m)[bad])))


def device_platform(device: str) -> str:
    """The platform ``--device`` names: "cpu" or "gpu" ("auto": the GPU when
    JAX has one); `InputError` for a GPU that is not there."""
    if device not in SWEEP_DEVICES:
        raise InputError(f"--device {device!r}; allowed: {', '.join(SWEEP_DEVICES)}")
    if device == "cpu":
        return "cpu"
    try:
        jax.devices("gpu")
    except RuntimeError:
        if device == "gpu":
            raise InputError(f"--device gpu: JAX sees no GPU here (backend "
                             f"{jax.default_backend()}); allowed: --device cpu or auto") from None
        return "cpu"
    return "gpu"


def how(info: dict) -> str:
    """How a sweep ran, in words."""
    if info.get("execution") == "pooled":
        return f"one point after another over {info['processes']} processes"
    if info.get("execution") == "looped":
        return "one point after another"
    if info.get("execution") == "batched":
        return f"vmapped in {info['chunks']} chunk(s) of {info['chunk_size']}"
    return f"{info.get('tasks', '?')} tasks on the Dask cluster"


def run(spec: SweepSpec, out: OutputDir, *, chunk_size: int | None = None, client=None,
        input_text: str | None = None, log=print, device: str = "auto",
        progress: bool = False) -> dict:
    """Run the sweep (locally on ``device``, or on the Dask ``client``) and
    write every output; ``progress``: a bar with points/s."""
    started = time.perf_counter()
    chunk = chunk_size if chunk_size is not None else spec.chunk_size
    axes = ", ".join(f"{k} x {v.size}" for k, v in spec.grid.items())
    if client is None:
        platform = device_platform(device)
        plan = ("one jitted run after another (over a process per core when that pays)"
                if platform == "cpu" else f"vmapped in chunks of {chunk or 'all that fit'}")
        log(f"[sweep] {spec.model_name}: {spec.points} points ({axes}) on the "
            f"{platform.upper()}: {plan}")
        execution = Auto() if platform == "cpu" else Batched(chunk)
        bar = tqdm(total=spec.points, unit="point", disable=not progress, desc="sweep",
                   mininterval=1.0)
        with bar, jax.default_device(jax.devices(platform)[0]):
            res = sweep(spec.model, spec.base, spec.grid, execution=execution,
                        progress=bar.update)
        res.info["device"] = platform
    else:
        from ..sweep.distributed import sweep_distributed

        log(f"[sweep] {spec.model_name}: {spec.points} points ({axes}) on the Dask cluster, "
            f"chunk size {chunk or 'all'}")
        res = sweep_distributed(spec.model, spec.base, spec.grid, client=client, chunk_size=chunk)
    wall = time.perf_counter() - started
    log(f"[sweep] done: {how(res.info)}; compile {res.info['compile_s']:.1f} s, run "
        f"{res.info['run_s']:.1f} s")
    return write(spec, res, out, input_text=input_text, wall_s=wall)


def write(spec: SweepSpec, res: SweepResult, out: OutputDir, *, input_text=None,
          wall_s: float = math.nan) -> dict:
    if input_text is not None:
        out.text("input.toml", input_text)
    cols = {column_name(spec, k): v for k, v in res.inputs.items()}
    cols |= res.outputs
    out.csv("results.csv", cols, fmt="%.17g")
    arrays: dict[str, Any] = {"grid_shape": np.asarray(res.grid_shape),
                              **{f"axis_{k}": res.axis(k) for k in res.grid_names}, **cols}
    np.savez(out.file("results.npz"), **arrays)
    netcdf = _netcdf(spec, res, out)

    figures = _figures(spec, res, out)
    bad = failed_points(res)
    outputs: dict[str, dict[str, Any]] = {}
    for k, col in res.outputs.items():
        ok = np.isfinite(col)
        if not ok.any():
            outputs[k] = {"min": None, "max": None}
            continue
        i_min = int(np.flatnonzero(ok)[np.argmin(col[ok])])
        i_max = int(np.flatnonzero(ok)[np.argmax(col[ok])])
        outputs[k] = {"min": float(col[i_min]), "max": float(col[i_max]),
                      "argmin": {g: shown_value(spec, g, res[g][i_min]) for g in res.grid_names},
                      "argmax": {g: shown_value(spec, g, res[g][i_max]) for g in res.grid_names}}
    info = res.info
    summary = {
        "file": spec.file, "title": spec.title, "model": spec.model_name,
        "settings": spec.settings,
        "base_si": {column_name(spec, k): v for k, v in spec.base.items()
                    if k not in spec.grid},
        "grid": {k: {"unit": spec.params[k].display_unit,
                     "values": [shown_value(spec, k, x) for x in v]}
                 for k, v in spec.grid.items()},
        "grid_si": {column_name(spec, k): v.tolist() for k, v in spec.grid.items()},
        "grid_shape": list(res.grid_shape), "points": len(res),
        "outputs": outputs,
        "failed_points": [int(i) for i in bad],
        "compile_s": info.get("compile_s"), "run_s": info.get("run_s"),
        "points_per_s": len(res) / info["run_s"] if info.get("run_s") else None,
        "device": info.get("device"), "execution": info.get("execution", "dask"),
        "processes": info.get("processes"),
        "chunk_size": info.get("chunk_size"), "devices": info.get("devices"),
        "workers": info.get("workers"), "wall_time_s": wall_s,
        "netcdf": netcdf,
    }
    out.text("report.md", render(_report(spec, res, summary, figures)))
    summary["files"] = [*out.files, "summary.json"]
    out.json("summary.json", summary)
    if bad.size:
        first = [{g: float(res[g][i]) for g in res.grid_names} for i in bad[:3]]
        raise SolverError(f"{spec.file}: {bad.size} of {len(res)} sweep points failed (outputs "
                          f"not finite or a failure status{failure_words(res, bad)}), e.g. "
                          f"{first}; every result is in {out.path}/results.csv")
    return summary


def _netcdf(spec: SweepSpec, res: SweepResult, out: OutputDir) -> str:
    try:
        from scipy.io import netcdf_file
    except ImportError:
        return "not written: SciPy is not installed (pip install 'diffwear[netcdf]')"
    with netcdf_file(out.file("results.nc"), "w") as nc:
        nc.title = spec.title or spec.file
        nc.model = spec.model_name
        for name in res.grid_names:
            nc.createDimension(name, res.axis(name).size)
            var = nc.createVariable(name, "d", (name,))
            var[:] = res.axis(name)
            var.units = column_name(spec, name)[len(name) + 1:] or "1"
        for k, col in res.outputs.items():
            var = nc.createVariable(k, "d", tuple(res.grid_names))
            var[:] = res.grid(k)
        for k, v in spec.base.items():
            if k not in spec.grid:
                setattr(nc, f"base_{column_name(spec, k)}", float(v))
    return "results.nc"


def _figures(spec: SweepSpec, res: SweepResult, out: OutputDir) -> list[str]:
    names = [k for k in res.outputs if k not in SKIP_PLOTS]
    title = spec.title or spec.model_name
    files = []
    if len(res.grid_names) == 1:
        (g,) = res.grid_names
        x = shown(spec, g, res.axis(g))
        for k in names:
            files.append(plots_sweep.line(out.file(f"{k}.png"), x, res.grid(k),
                                          xlabel=label(spec, g),
                                          ylabel=plots_sweep.quantity(k),
                                          title=f"{title}: {_words(k)}").name)
    elif len(res.grid_names) == 2:
        gy, gx = res.grid_names
        x, y = shown(spec, gx, res.axis(gx)), shown(spec, gy, res.axis(gy))
        for k in names:
            files.append(plots_sweep.heatmap(out.file(f"{k}.png"), x, y, res.grid(k),
                                             xlabel=label(spec, gx), ylabel=label(spec, gy),
                                             zlabel=plots_sweep.quantity(k),
                                             title=f"{title}: {_words(k)}").name)
    return files


def _settings_words(settings: dict) -> str:
    """"cycles 21,400, dynamic_cycles 50, wear_model quasi-static"."""
    if not settings:
        return "(defaults)"
    return ", ".join(f"{k} {v:,.6g}" if isinstance(v, float) else f"{k} {v}"
                     for k, v in settings.items())


def _words(output: str) -> str:
    """An output's name in words, without its unit: "max_depth_mm" -> "max wear depth"."""
    return plots_sweep.quantity(output).split(" [")[0]


def _report(spec: SweepSpec, res: SweepResult, summary: dict, figures: list[str]) -> Report:
    outputs = []
    for k, s in summary["outputs"].items():
        if s["min"] is None:
            outputs.append((k, "-", "-", "-"))
            continue
        at = ", ".join(with_unit(spec, g, v / spec.params[g].display_scale)
                       for g, v in s["argmax"].items())
        outputs.append((f"{plots_sweep.quantity(k)} (`{k}`)", f"{s['min']:.6g}",
                        f"{s['max']:.6g}", at))
    pps = summary["points_per_s"]
    failed = summary["failed_points"]
    blocks: list[Block] = [
        f"Model `{spec.model_name}` from `{spec.file}`; settings "
        f"{_settings_words(spec.settings)}; {len(res)} points "
        f"({' x '.join(f'{g} {n}' for g, n in zip(res.grid_names, res.grid_shape))}).",
        Table(("axis", "values"),
              [(label(spec, g), ", ".join(f"{v:.4g}" for v in shown(spec, g, res.axis(g))))
               for g in res.grid_names]),
        Table(("output", "min", "max", "max at"), outputs, align="lrrl"),
        f"**{len(failed)} point(s) failed** (indices in summary.json `failed_points`)."
        if failed else "",
        f"Run {how(res.info)}"
        + (f" on the {summary['device'].upper()}" if summary["device"] else "")
        + f": compile {summary['compile_s']:.1f} s, run {summary['run_s']:.1f} s"
        + (f" ({pps:.2f} points/s)" if pps else "") + ".",
        "Tables: [results.csv](results.csv), [results.npz](results.npz)"
        + (", [results.nc](results.nc)" if summary["netcdf"] == "results.nc" else "")
        + ", [summary.json](summary.json), [input.toml](input.toml).",
        *(Figure(f) for f in figures),
        "No figures for a grid of more than 2 axes: see the tables."
        if not figures and len(res.grid_names) > 2 else "",
    ]
    return Report(f"sweep: {spec.title or spec.model_name}", blocks)


__all__ = ["run", "write", "column_name", "failed_points"]
