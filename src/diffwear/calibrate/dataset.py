"""Measured wear data: a folder with ``dataset.toml`` and CSV files.

`load_dataset` reads a folder into a `Dataset` (everything in SI units);
`write_dataset` writes one (used by data generators) so that loading it back
gives the same values to ~1 ulp.  The format is documented in the docs ("Dataset format")
("The dataset format").

Every problem raises `InputError` naming the file (``dataset.toml`` or the
CSV), the key path or the CSV line and column, the bad value and what is
allowed, in the style of the mechanism files (`diffwear.config.loader`):

    data/dataset.toml: series[1].uncertainty: unit 'um' is a length unit, not volume; ...
    data/profile_02000.csv: line 7, column 'depth_um': '-40' is 8.0 uncertainties below zero; ...

Loading only reads: a failed load leaves the folder as it was.
"""

from __future__ import annotations

import dataclasses
import math
import re
import tempfile
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ..config import units
from ..config.loader import decode, read_input
from ..config.schema import (
    Context,
    Field,
    Number,
    Quantity,
    Text,
    check_unknown,
    read_array_of_tables,
    read_table,
    show,
    suggest,
    toml_type,
)
from ..errors import InputError
from .parameters import RIG_PARAMETERS

MANIFEST = "dataset.toml"
SECTIONS = ("dataset", "rig", "parameters", "calibration", "series")
PRESETS = ("rig",)  # the thesis Ch. 7 rig (`diffwear.presets.rig_slider_crank`)
ANGLE_SENSES = ("counter-clockwise", "clockwise")  # of the profile files' bushing angle
ROLES = ("fit", "holdout")
BASES = ("mass", "profile")
NAME_PATTERN = re.compile(r"[A-Za-z0-9_.-]+")
NAME_RULE = "letters, digits, '_', '.' or '-' (at least one)"
FOLDER_RULE = f"a dataset folder holding {MANIFEST} and its CSV files"

# parameter name -> dimension (None: a plain number); the table: `parameters`
PARAMETERS: dict[str, str | None] = {n: p.dimension for n, p in RIG_PARAMETERS.items()}
# SI units of the rig's numbers in a report (a dataset's own units are
# converted on loading: k in mm^3/(N m) is 1e-9 1/Pa)
REPORT_UNITS = {"wear coefficient": "1/Pa = m^3/(N m)", "length": "m", None: "-",
                "mass": "kg", "inertia": "kg m^2", "stiffness": "N/m"}
PARAMETER_RULE = ("k (wear coefficient); clearance, depth, diameter, wall, free_length, "
                  "crank_length, rod_length (lengths); spring_stiffness (N/m); crank_mass, "
                  "rod_mass, slider_mass (masses); crank_inertia, rod_inertia (kg m^2); "
                  "mu (plain number in [0, 1])")


# ----------------------------------------------------------------------------- data classes
def _frozen_array(values, dtype) -> np.ndarray:
    a = np.array(values, dtype=dtype).reshape(-1)
    a.flags.writeable = False
    return a


@dataclass(frozen=True)
class Parameter:
    """A rig parameter: its SI value (None: the preset's), whether calibration
    fits it, and whether it may be named as a suspect when no wear effect
    explains the data (mechanism parameters only; default yes)."""

    name: str
    value: float | None
    std: float | None = None  # 1-sigma prior width, SI
    fit: bool = False
    suspect: bool = True
    # the unit the dataset wrote it in (reports use it; not part of its value)
    unit: str | None = field(default=None, compare=False)
    # one SI unit of it in ``unit`` (found when the dataset loads)
    per_si: float = field(default=1.0, compare=False)


@dataclass(frozen=True, eq=False)
class Series:
    """One measured series, in SI units.

    ``file`` is relative to the dataset folder (`Dataset.path`).  ``x`` is the
    angle [rad] of a profile (bushing frame) or force (crank angle) series and
    the cycle count of a volume / max_depth series; ``y`` is depth [m], volume
    [m^3], max depth [m] or force [N]; ``sigma`` the 1-sigma noise of ``y``.
    ``holdout[i]`` marks points kept out of the fit.  Arrays are read-only.
    """

    name: str
    kind: str
    file: Path
    cycles: float | None
    x: np.ndarray
    y: np.ndarray
    sigma: float
    holdout: np.ndarray = None  # type: ignore[assignment]  # None: nothing held out
    basis: str | None = None    # volume series: "mass" | "profile"

    def __post_init__(self):
        x = _frozen_array(self.x, float)
        set_ = object.__setattr__
        set_(self, "file", Path(self.file))
        set_(self, "x", x)
        set_(self, "y", _frozen_array(self.y, float))
        set_(self, "sigma", float(self.sigma))
        set_(self, "cycles", None if self.cycles is None else float(self.cycles))
        holdout = np.zeros(x.shape, bool) if self.holdout is None else self.holdout
        set_(self, "holdout", _frozen_array(holdout, bool))

    @property
    def cycle_counts(self) -> np.ndarray:
        """Cycle count of each point (a profile's or force's points share one)."""
        if KINDS[self.kind].cycles_key:
            return np.full(self.x.shape, self.cycles)
        return self.x


@dataclass(frozen=True, eq=False)
class Dataset:
    """A loaded dataset: manifest values and series, SI units throughout."""

    name: str
    description: str
    path: Path
    preset: str
    parameters: dict[str, Parameter]
    series: tuple[Series, ...]
    bushing_density: float | None = None     # kg/m^3
    holdout_from_cycles: float | None = None
    mechanism: Path | None = None            # a mechanism file instead of the preset
    joint: str | None = None                 # its wearing joint (None: the only one)
    notes: tuple[str, ...] = field(default=())  # non-fatal remarks, e.g. "no holdout data"

    @property
    def max_cycles(self) -> float:
        """The largest cycle count of any measurement."""
        return max(float(np.max(s.cycle_counts)) for s in self.series)

    @property
    def fit_cycles(self) -> float:
        """The end of the fit window: the largest cycle count of a fitted (not
        held-out) wear measurement (profile, volume or depth); `max_cycles`
        when no wear measurement is fitted.  Everything the calibration
        chooses is computed on [0, fit_cycles], so that deleting the held-out
        measurements leaves it unchanged."""
        counts = [float(np.max(np.broadcast_to(s.cycle_counts, s.holdout.shape)[~s.holdout]))
                  for s in self.series if s.kind != "force" and not s.holdout.all()]
        return max(counts) if counts else self.max_cycles

    @property
    def fit_names(self) -> tuple[str, ...]:
        """Names of the parameters with ``fit = true``, in `PARAMETERS` order."""
        return tuple(n for n, p in self.parameters.items() if p.fit)

    def unit_of(self, name: str) -> str | None:
        """The unit a fitted number ``name`` is reported in: the dataset's own
        for its parameters, SI (`REPORT_UNITS`) for the rest of the rig's."""
        p = self.parameters.get(name)
        if p is not None and p.unit:
            return p.unit
        return REPORT_UNITS.get(PARAMETERS[name]) if name in PARAMETERS else None

    def in_own_unit(self, name: str, values) -> np.ndarray:
        """``values`` of ``name`` (SI) in the unit `unit_of` gives."""
        p = self.parameters.get(name)
        return np.asarray(values) * (p.per_si if p is not None and p.unit else 1.0)

    def label(self, name: str) -> str:
        """``name`` with its unit, for a table's column or a figure's axis."""
        unit = self.unit_of(name)
        return f"{name.replace('_', ' ')}" + (f" [{unit}]" if unit else "")

    def file_of(self, series: Series) -> Path:
        """The CSV path of ``series``."""
        return self.path / series.file


# ----------------------------------------------------------------------------- series kinds
class Column(NamedTuple):
    dimension: str | None  # None: a plain number (cycles)
    unit: str | None


COLUMNS: dict[str, Column] = {
    "theta_rad": Column("angle", "rad"),
    "theta_deg": Column("angle", "deg"),
    "depth_mm": Column("length", "mm"),
    "depth_um": Column("length", "um"),
    "cycles": Column(None, None),
    "volume_mm3": Column("volume", "mm^3"),
    "mass_g": Column("mass", "g"),
    "mass_mg": Column("mass", "mg"),
    "max_depth_mm": Column("length", "mm"),
    "max_depth_um": Column("length", "um"),
    "crank_angle_rad": Column("angle", "rad"),
    "crank_angle_deg": Column("angle", "deg"),
    "force_N": Column("force", "N"),
}


class Kind(NamedTuple):
    x: tuple[str, ...]       # one of these columns gives x
    y: tuple[str, ...]       # one of these gives y
    quantity: str            # dimension of y and of the uncertainty
    cycles_key: bool         # True: `cycles` in the manifest; False: a cycles column
    y_nonnegative: bool      # physically >= 0: only noise may take it below (NOISE_SIGMAS)
    write: tuple[str, str]   # columns write_dataset uses
    write_unit: str          # unit of the y column written (and of the uncertainty)


KINDS: dict[str, Kind] = {
    "profile": Kind(("theta_rad", "theta_deg"), ("depth_mm", "depth_um"), "length", True, True,
                    ("theta_rad", "depth_mm"), "mm"),
    "volume": Kind(("cycles",), ("volume_mm3", "mass_g", "mass_mg"), "volume", False, True,
                   ("cycles", "volume_mm3"), "mm^3"),
    "max_depth": Kind(("cycles",), ("max_depth_mm", "max_depth_um"), "length", False, True,
                      ("cycles", "max_depth_mm"), "mm"),
    "force": Kind(("crank_angle_rad", "crank_angle_deg"), ("force_N",), "force", True, False,
                  ("crank_angle_rad", "force_N"), "N"),
}

_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)
_NON_FINITE = {"nan", "inf", "infinity"}
_TWO_PI = 2.0 * math.pi


# ----------------------------------------------------------------------------- manifest fields
@dataclass(frozen=True)
class Flag(Field):
    """``true`` / ``false``."""

    def expects(self, key):
        return "true or false"

    def read(self, ctx, path, key, spelling, raw):
        if not isinstance(raw, bool):
            raise ctx.error(path, f"expected true or false, got {toml_type(raw)} {show(raw)}",
                            "true or false")
        return raw


@dataclass(frozen=True)
class VolumeOrMass(Field):
    """A positive volume, or a mass (of a weighed series); reads ``(SI value, dimension)``."""

    def _quantity(self, dimension):
        return Quantity(dimension=dimension, low=0.0, low_open=True)

    def spellings(self, key):
        return (key, *self._quantity("volume").spellings(key)[1:],
                *self._quantity("mass").spellings(key)[1:])

    def expects(self, key):
        return (f"a volume ({units.allowed_units('volume')}), e.g. {key} = \"2 mm^3\", or for a "
                f"weighed series a mass ({units.allowed_units('mass')}), e.g. {key} = \"0.5 mg\"")

    def read(self, ctx, path, key, spelling, raw):
        dimension = None
        if spelling != key:
            mass = self._quantity("mass").spellings(key)[1:]
            dimension = "mass" if spelling in mass else "volume"
        elif isinstance(raw, str):
            for d in ("volume", "mass"):
                try:
                    units.parse_quantity(raw, d)
                    dimension = d
                    break
                except InputError:
                    pass
        if dimension is None:  # neither: report it as a volume, naming the mass option
            try:
                self._quantity("volume").read(ctx, path, key, spelling, raw)
            except InputError as err:
                raise InputError(f"{err} (or, for a weighed series, a mass: "
                                 f"{units.allowed_units('mass')}, e.g. '0.5 mg')") from None
        return self._quantity(dimension).read(ctx, path, key, spelling, raw), dimension


def _parameter_fields(dimension: str | None, signed: bool = False) -> dict[str, Field]:
    """A parameter's keys; ``signed``: a mechanism-file number (a point may be
    negative; a plain number is not limited to [0, 1])."""
    flags = {"fit": Flag(default=False), "suspect": Flag(default=True)}
    if dimension is None:
        value = Number(default=None) if signed else Number(default=None, low=0.0, high=1.0)
        return {"value": value, "std": Number(default=None, low=0.0, low_open=True), **flags}
    if signed:
        return {"value": Quantity(dimension=dimension, default=None),
                "std": Quantity(dimension=dimension, default=None, low=0.0, low_open=True),
                **flags}
    return {"value": Quantity(dimension=dimension, default=None, low=0.0, low_open=True),
            "std": Quantity(dimension=dimension, default=None, low=0.0, low_open=True),
            **flags}


DATASET_FIELDS = {"name": Text(), "description": Text(default="")}
RIG_FIELDS = {
    "preset": Text(default=None, choices=PRESETS),
    # or a mechanism file (path relative to the dataset folder) and its wearing joint
    "mechanism": Text(default=None),
    "joint": Text(default=None),
    "bushing_density": Quantity(dimension="density", default=None, low=0.0, low_open=True),
    # the bushing angle of the profile files: where their 0 lies in the model's
    # bushing frame (counter-clockwise from the rod axis, crank -> slider end)
    # and which way they count
    "bushing_angle_zero": Quantity(dimension="angle", default=0.0, low=-2 * math.pi,
                                   high=2 * math.pi),
    "bushing_angle_sense": Text(default=ANGLE_SENSES[0], choices=ANGLE_SENSES),
}
CALIBRATION_FIELDS = {"holdout_from_cycles": Number(default=None, low=0.0)}


def _series_fields(kind: str) -> dict[str, Field]:
    spec = KINDS[kind]
    fields: dict[str, Field] = {"kind": Text(), "file": Text()}
    if spec.cycles_key:
        fields["cycles"] = Number(low=0.0)
    fields["uncertainty"] = (VolumeOrMass() if kind == "volume" else
                             Quantity(dimension=spec.quantity, low=0.0, low_open=True))
    fields["role"] = Text(default=None, choices=ROLES)
    if kind == "volume":
        fields["basis"] = Text(default=None, choices=BASES)
    fields["name"] = Text(default=None)
    return fields


# ----------------------------------------------------------------------------- loading
def load_dataset(folder: str | Path) -> Dataset:
    """Read a dataset folder; raise `InputError` naming the file for any problem."""
    folder = Path(folder)
    if not folder.exists():
        raise InputError(f"{folder}: no such folder; allowed: {FOLDER_RULE}")
    if not folder.is_dir():
        raise InputError(f"{folder}: is a file, not a folder; allowed: {FOLDER_RULE}")
    manifest = folder / MANIFEST
    file = str(manifest)
    data = read_input(manifest, FOLDER_RULE)
    text = decode(data, file)
    if not text.strip():
        raise InputError(f"{file}: the file is empty; allowed: a TOML manifest with [dataset], "
                         "[rig], [parameters] and [[series]]")
    try:
        parsed = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise InputError(f"{file}: invalid TOML: {err}; allowed: TOML 1.0 syntax "
                         "(https://toml.io)") from None
    return _build(folder, Context(file), parsed)


def _section(ctx: Context, data: Mapping, key: str, fields: Mapping[str, Field], *,
             required: bool, example: str) -> dict:
    raw = data.get(key)
    if raw is None:
        if required:
            raise ctx.error(key, "missing section", f"[{key}] with {example}")
        raw = {}
    return read_table(ctx, key, _table(ctx, key, raw, f"[{key}] with {example}"), fields)


def _build(folder: Path, ctx: Context, data: Mapping) -> Dataset:
    if not data:
        raise ctx.error("(top level)", "the file holds no keys or tables (only comments?)",
                        "[dataset], [rig], [parameters], [calibration], [[series]]")
    check_unknown(ctx, "", data, SECTIONS)
    head = _section(ctx, data, "dataset", DATASET_FIELDS, required=True,
                    example='name = "run-in-1"')
    if NAME_PATTERN.fullmatch(head["name"]) is None:
        raise ctx.error("dataset.name", f"{head['name']!r} is not a valid name", NAME_RULE)
    rig = _section(ctx, data, "rig", RIG_FIELDS, required=True, example='preset = "rig"')
    calibration = _section(ctx, data, "calibration", CALIBRATION_FIELDS, required=False,
                           example="holdout_from_cycles = 3000")
    mechanism = _mechanism(ctx, folder, rig)
    parameters = _parameters(ctx, data.get("parameters"), mechanism)
    holdout_from = calibration["holdout_from_cycles"]
    series: list[Series] = []
    names: dict[str, int] = {}
    raw_series = read_array_of_tables(ctx, "series", data.get("series"), required=True)
    for k, table in enumerate(raw_series):
        s = _series(ctx, folder, k, table, rig["bushing_density"], holdout_from)
        if s.kind == "profile":
            s = _to_model_frame(s, rig["bushing_angle_zero"], rig["bushing_angle_sense"])
        if s.name in names:
            raise ctx.error(f"series[{k}].name",
                            f"{s.name!r} is already the name of series[{names[s.name]}]",
                            "unique series names (set name = \"...\"; default: the file stem)")
        names[s.name] = k
        series.append(s)
    n_points = sum(s.x.size for s in series)
    n_held = sum(int(s.holdout.sum()) for s in series)
    if n_held == n_points:
        why = ("role = \"holdout\"" if holdout_from is None
               else f"holdout_from_cycles = {holdout_from:g} or role = \"holdout\"")
        raise ctx.error("series", f"all {n_points} measurements of the {len(series)} series are "
                        f"held out ({why}): nothing is left to fit",
                        "at least one measurement to fit: a series with role = \"fit\", or "
                        "holdout_from_cycles above the cycle count of some measurement")
    notes = () if n_held else ("no measurement is held out: the fit cannot be checked on "
                               "unseen data",)
    return Dataset(
        name=head["name"], description=head["description"], path=folder,
        preset=rig["preset"], parameters=parameters, series=tuple(series),
        mechanism=None if mechanism is None else mechanism[0], joint=rig["joint"],
        bushing_density=rig["bushing_density"], holdout_from_cycles=holdout_from, notes=notes,
    )


def _to_model_frame(s: "Series", zero: float, sense: str) -> "Series":
    """A profile measured with its own angle convention, in the model's bushing
    frame: theta = zero + theta_data (counter-clockwise) or zero - theta_data
    (clockwise), wrapped to [0, 2 pi) and sorted."""
    if zero == 0.0 and sense == ANGLE_SENSES[0]:
        return s
    sign = 1.0 if sense == ANGLE_SENSES[0] else -1.0
    theta = np.mod(zero + sign * np.asarray(s.x), 2 * math.pi)
    theta = np.where(theta >= 2 * math.pi, 0.0, theta)  # mod can round up to 2 pi
    order = np.argsort(theta, kind="stable")
    return dataclasses.replace(s, x=theta[order], y=np.asarray(s.y)[order],
                               holdout=np.asarray(s.holdout)[order])


def _mechanism(ctx: Context, folder: Path, rig: dict):
    """(path, parsed TOML) of ``[rig] mechanism``, or None for the preset."""
    if (rig["preset"] is None) == (rig["mechanism"] is None):
        given = "both" if rig["preset"] is not None else "neither"
        raise ctx.error("rig", f"{given} of preset and mechanism given",
                        'exactly one: preset = "rig" or mechanism = "<file>.toml" (a mechanism '
                        "file, relative to the dataset folder)")
    if rig["mechanism"] is None:
        if rig["joint"] is not None:
            raise ctx.error("rig.joint", "joint is for a mechanism file",
                            "the preset rig's wearing joint is fixed (crank_rod)")
        return None
    from ..config.loader import load, resolve, shipped_mechanisms

    path = Path(rig["mechanism"])
    path = path if path.is_absolute() else folder / path
    if not path.is_file():
        path = resolve(rig["mechanism"])  # a shipped mechanism by name
    if not path.is_file():
        raise ctx.error("rig.mechanism", f"{rig['mechanism']!r}: no such file (looked for "
                        f"{folder / rig['mechanism']})", "a mechanism file, relative to the "
                        "dataset folder, or a shipped mechanism: "
                        + ", ".join(shipped_mechanisms()))

    study = load(path)  # a bad mechanism file reports itself, by name
    return path, tomllib.loads(path.read_text(encoding="utf-8")), study


def _parameters(ctx: Context, raw, mechanism=None) -> dict[str, Parameter]:
    example = 'k = { value = "5.05e-4 mm^3/(N m)", fit = true }'
    if mechanism is not None:
        example = '"joints.crank_rod.wear.coefficient" = { fit = true, std = "1e-4 mm^3/(N m)" }'
    if raw is None:
        raise ctx.error("parameters", "missing section", f"[parameters] with e.g. {example}")
    table = _table(ctx, "parameters", raw, f"[parameters] with <name> = {{ value, std, fit }}, "
                   f"e.g. {example}")
    if mechanism is None:
        for name in table:
            if name not in PARAMETERS:
                raise ctx.error(f"parameters.{name}",
                                f"unknown parameter {name!r}{suggest(name, list(PARAMETERS))}",
                                PARAMETER_RULE)
        dims = {n: d for n, d in PARAMETERS.items() if n in table}  # canonical order
    else:
        from .mechanism_file import file_value

        path, doc, _ = mechanism
        dims = {}
        for name in table:
            try:
                dims[name] = file_value(doc, name, str(path))[1]
            except InputError as err:
                raise ctx.error(f"parameters.{name}", str(err),
                                "a number of the mechanism file by its path, e.g. "
                                "\"bodies.rod.mass\"") from None
    out = {}
    for name, dimension in dims.items():
        path = f"parameters.{name}"
        entry = _table(ctx, path, table[name], f"{name} = {{ value = ..., std = ..., fit = ... }}")
        fields = _parameter_fields(dimension, signed=mechanism is not None)
        v = read_table(ctx, path, entry, fields)
        if v["fit"] and v["value"] is None and mechanism is None:
            raise ctx.error(f"{path}.value", "missing: a fitted parameter needs its starting "
                            "value", f"{name} = {{ value = ..., std = ..., fit = true }}")
        written = entry.get("value", entry.get("std"))
        unit = (units.unit_of(written, dimension)
                if isinstance(written, str) and dimension else None)
        out[name] = Parameter(name, v["value"], v["std"], v["fit"], v["suspect"], unit,
                              units.in_unit(1.0, unit, dimension) if unit and dimension else 1.0)
    if not any(p.fit for p in out.values()):
        given = ", ".join(out) or "(none)"
        rule = PARAMETER_RULE if mechanism is None else "numbers of the mechanism file by path"
        raise ctx.error("parameters", f"no parameter has fit = true (given: {given})",
                        f"fit = true on at least one parameter to calibrate: {rule}")
    return out


def _table(ctx: Context, path: str, raw, allowed: str) -> dict:
    if not isinstance(raw, dict):
        raise ctx.error(path, f"expected a table, got {toml_type(raw)} {show(raw)}", allowed)
    return raw


def _series(ctx: Context, folder: Path, k: int, table: dict, density: float | None,
            holdout_from: float | None) -> Series:
    path = f"series[{k}]"
    kind = table.get("kind")
    kinds = ", ".join(repr(s) for s in KINDS)
    if kind is None:
        raise ctx.error(f"{path}.kind", "missing key", kinds)
    if not isinstance(kind, str):
        raise ctx.error(f"{path}.kind", f"expected a string, got {toml_type(kind)} {show(kind)}",
                        kinds)
    if kind not in KINDS:
        raise ctx.error(f"{path}.kind", f"unknown series kind {kind!r}"
                        f"{suggest(kind, list(KINDS))}", kinds)
    spec = KINDS[kind]
    if "cycles" in table and not spec.cycles_key:
        raise ctx.error(f"{path}.cycles", f"not allowed for a {kind} series (its CSV has a "
                        "cycles column, one count per row)",
                        "remove the key; cycles = <count> is for profile and force series")
    if "cycles" not in table and spec.cycles_key:
        raise ctx.error(f"{path}.cycles", f"missing key (the cycle count at which the {kind} "
                        "was measured)", "cycles = <count> >= 0, e.g. cycles = 2000")
    if "basis" in table and kind != "volume":
        raise ctx.error(f"{path}.basis", f"not allowed for a {kind} series",
                        "basis only on volume series")
    v = read_table(ctx, path, table, _series_fields(kind))
    rel = _relative_file(ctx, folder, f"{path}.file", v["file"])
    name = v["name"] if v["name"] is not None else rel.stem
    if NAME_PATTERN.fullmatch(name) is None:
        where = f"{path}.name" if v["name"] is not None else f"{path}.file"
        what = (f"{name!r} is not a valid series name" if v["name"] is not None else
                f"the file stem {name!r} is not a valid series name (set name = \"...\")")
        raise ctx.error(where, what, NAME_RULE)

    csv = _read_csv(folder / rel, kind)
    y, sigma, basis = csv.y, v["uncertainty"], v.get("basis")
    if kind == "volume":
        sigma, sigma_dim = sigma
        column_dim = COLUMNS[csv.y_column].dimension
        if column_dim == "mass":
            if basis == "profile":
                raise ctx.error(f"{path}.basis", f"'profile' contradicts the column "
                                f"{csv.y_column!r} of {rel} (a weighed mass)",
                                "'mass' or leave basis out")
            basis = "mass"
        elif basis is None:
            raise ctx.error(f"{path}.basis", f"missing key ({rel} gives volume_mm3: say how the "
                            "volume was measured)", "'mass' (from weighing) or 'profile' "
                            "(integrated profile)")
        if sigma_dim == "mass" and basis != "mass":
            raise ctx.error(f"{path}.uncertainty", f"{show(table.get('uncertainty'))} is a mass, "
                            "but the series is an integrated profile (basis = 'profile')",
                            "a volume, e.g. \"2 mm^3\"")
        needs = [what for what, dim in ((f"column {csv.y_column!r}", column_dim),
                                        ("its uncertainty", sigma_dim)) if dim == "mass"]
        if needs and density is None:
            raise ctx.error("rig.bushing_density",
                            f"missing key ({path} ({rel}) gives {' and '.join(needs)} as a mass, "
                            "which needs the bushing density to become a volume)",
                            'bushing_density = "2.25 g/cm^3" (units: '
                            f'{units.allowed_units("density")})')
        if column_dim == "mass":
            y = y / density
        if sigma_dim == "mass":
            sigma = sigma / density
    if spec.y_nonnegative:
        _check_noise_floor(str(folder / rel), csv, y, sigma)

    cycles = v.get("cycles")
    if v["role"] is not None:
        holdout = np.full(csv.x.shape, v["role"] == "holdout")
    elif holdout_from is None:
        holdout = np.zeros(csv.x.shape, bool)
    else:
        counts = np.full(csv.x.shape, cycles) if spec.cycles_key else csv.x
        holdout = counts >= holdout_from
    return Series(name=name, kind=kind, file=rel, cycles=cycles, x=csv.x, y=y, sigma=sigma,
                  holdout=holdout, basis=basis)


def _relative_file(ctx: Context, folder: Path, path: str, text: str) -> Path:
    allowed = "a path relative to the dataset folder, inside it, e.g. \"profile_02000.csv\""
    if not text.strip():
        raise ctx.error(path, "empty file name", allowed)
    rel = Path(text)
    if rel.is_absolute():
        raise ctx.error(path, f"{text!r} is an absolute path", allowed)
    target = folder / rel
    try:
        target.resolve().relative_to(folder.resolve())
    except ValueError:
        raise ctx.error(path, f"{text!r} points outside the dataset folder {folder}",
                        allowed) from None
    if not target.exists():
        raise ctx.error(path, f"{text!r}: no such file in {folder}", allowed)
    if not target.is_file():
        raise ctx.error(path, f"{text!r} is not a file", allowed)
    return rel


# ----------------------------------------------------------------------------- CSV
class _Csv(NamedTuple):
    x_column: str
    y_column: str
    x: np.ndarray
    y: np.ndarray
    lines: tuple[int, ...]   # the file's line of each point
    cells: tuple[str, ...]   # the y cell as written


# A depth, volume or mass is >= 0, but its measurement is not: a profilometer
# reads noise around zero in the unworn arc.  Values down to this many
# uncertainties below zero are kept as measured (clipping them would bias the
# fit); a value further below is a mistake in the data (P < 3e-5 for noise).
NOISE_SIGMAS = 4.0


def _csv_error(file: str, line: int, column: str | None, what: str, allowed: str) -> InputError:
    where = f"line {line}" + (f", column {column!r}" if column is not None else "")
    return InputError(f"{file}: {where}: {what}; allowed: {allowed}")


def _columns_rule(spec: Kind) -> str:
    return f"{' or '.join(spec.x)}, and {' or '.join(spec.y)}"


def _header(file: str, line: int, cells: list[str], kind: str) -> tuple[str, str]:
    spec = KINDS[kind]
    rule = f"a header naming the columns of a {kind} series: {_columns_rule(spec)}"
    if all(_NUMBER.fullmatch(c) for c in cells):
        raise _csv_error(file, line, None, f"the header row is missing (found numbers: "
                         f"{show(','.join(cells))})", rule)
    allowed = (*spec.x, *spec.y)
    seen = set()
    for c in cells:
        if not c:
            raise _csv_error(file, line, None,
                             f"empty column name in header {show(','.join(cells))}", rule)
        if c in seen:
            raise _csv_error(file, line, c, "the column is named twice", rule)
        seen.add(c)
    extra = [c for c in cells if c not in allowed]
    if extra:
        hints = "".join(suggest(c, list(allowed)) for c in extra[:1])
        other = [c for c in extra if c in COLUMNS]
        note = f" ({other[0]!r} belongs to another kind of series)" if other and not hints else ""
        raise _csv_error(file, line, None, f"unknown column{'s' if len(extra) > 1 else ''} "
                         f"{', '.join(repr(c) for c in extra)}{hints}{note}", rule)
    chosen = []
    for group in (spec.x, spec.y):
        given = [c for c in cells if c in group]
        if not given:
            raise _csv_error(file, line, None, f"missing column: one of {', '.join(group)} "
                             f"(header: {show(','.join(cells))})", rule)
        if len(given) > 1:
            raise _csv_error(file, line, None, f"columns {' and '.join(given)} give the same "
                             "quantity", f"exactly one of {', '.join(group)}")
        chosen.append(given[0])
    return chosen[0], chosen[1]


def _cell(file: str, line: int, column: str, text: str) -> float:
    allowed = "a finite decimal number such as 0.25 or 1.5e-3"
    if _NUMBER.fullmatch(text) is None:
        if text.lower().lstrip("+-") in _NON_FINITE:
            raise _csv_error(file, line, column, f"{text!r} is not finite", allowed)
        if not text:
            raise _csv_error(file, line, column, "empty cell", allowed)
        raise _csv_error(file, line, column, f"{show(text)} is not a number", allowed)
    value = float(text)
    dimension, unit = COLUMNS[column]
    try:
        if not math.isfinite(value):
            raise InputError("")
        si = value if dimension is None or unit is None else units.to_si(value, unit, dimension)
    except InputError:
        raise _csv_error(file, line, column, f"{text!r} is out of the float64 range",
                         allowed) from None
    return si


def _read_csv(path: Path, kind: str) -> _Csv:
    file = str(path)
    spec = KINDS[kind]
    try:
        data = path.read_bytes()
    except OSError as err:
        raise InputError(f"{file}: cannot be read ({err.strerror})") from None
    text = decode(data, file, note="CSV files are UTF-8")
    header = None
    rows: list[tuple[int, list[str]]] = []
    for number, raw in enumerate(text.split("\n"), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        cells = [c.strip() for c in line.split(",")]
        if header is None:
            header = (number, cells)
        else:
            rows.append((number, cells))
    columns_rule = f"a header row ({_columns_rule(spec)}), then one row per point"
    if header is None:
        raise InputError(f"{file}: the file is empty (no header row); allowed: {columns_rule}")
    x_col, y_col = _header(file, header[0], header[1], kind)
    if not rows:
        raise InputError(f"{file}: no data rows below the header (line {header[0]}); "
                         f"allowed: {columns_rule}")
    names = header[1]
    ix, iy = names.index(x_col), names.index(y_col)
    x, y = np.empty(len(rows)), np.empty(len(rows))
    for r, (number, cells) in enumerate(rows):
        if len(cells) != len(names):
            raise _csv_error(file, number, None, f"{len(cells)} cells, but the header "
                             f"(line {header[0]}) names {len(names)} columns",
                             f"{len(names)} comma-separated numbers per row")
        x[r] = _cell(file, number, x_col, cells[ix])
        y[r] = _cell(file, number, y_col, cells[iy])
        if r and not x[r] > x[r - 1]:
            raise _csv_error(file, number, x_col, f"{cells[ix]!r} is not greater than the "
                             f"value on line {rows[r - 1][0]} ({rows[r - 1][1][ix]!r})",
                             f"strictly increasing {x_col}")
        if COLUMNS[x_col].dimension == "angle":
            if not 0.0 <= x[r] < _TWO_PI:
                top = "360" if x_col.endswith("_deg") else "2 pi = 6.283185307179586"
                raise _csv_error(file, number, x_col, f"{cells[ix]!r} is outside [0, 2 pi)",
                                 f"0 <= {x_col} < {top}")
        elif x[r] < 0.0:
            raise _csv_error(file, number, x_col, f"{cells[ix]!r} is negative",
                             f"{x_col} >= 0")
    return _Csv(x_col, y_col, x, y, tuple(n for n, _ in rows),
                tuple(cells[iy] for _, cells in rows))


def _check_noise_floor(file: str, csv: _Csv, y, sigma) -> None:
    """A quantity that is >= 0 may read below zero by noise only: at most
    `NOISE_SIGMAS` uncertainties."""
    floor = -NOISE_SIGMAS * float(sigma)
    for r in np.flatnonzero(np.asarray(y) < floor):
        raise _csv_error(file, csv.lines[r], csv.y_column,
                         f"{csv.cells[r]!r} is {-float(y[r]) / float(sigma):.1f} uncertainties "
                         "below zero (negative values are accepted as measurement noise down "
                         f"to {NOISE_SIGMAS:g} uncertainties)",
                         f"{csv.y_column} >= -{NOISE_SIGMAS:g} x the series' uncertainty")


# ----------------------------------------------------------------------------- writing
def _num(value: float) -> str:
    """Shortest text that reads back as the same float (integers without '.0')."""
    value = float(value)
    if value.is_integer() and abs(value) < 2**53:
        return str(int(value))
    return repr(value)


def _toml_string(text: str) -> str:
    out = []
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ch == "\n":
            out.append("\\n")
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _in_unit(value: float, scale) -> str:
    """Text of SI ``value`` in a unit of SI factor ``scale`` (a Fraction) that the
    loader reads back (``float(Fraction(text) * scale)``) as ``value`` exactly
    where one of the nearest floats does so, else to ~1 ulp."""
    value = float(value)
    if scale == 1 or not math.isfinite(value):
        return _num(value)
    first = float(Fraction(value) / scale)
    candidate = first
    for _ in range(3):
        for c in (candidate, math.nextafter(candidate, math.inf),
                  math.nextafter(candidate, -math.inf)):
            if float(Fraction(repr(c)) * scale) == value:
                return _num(c)
        candidate = math.nextafter(candidate, math.inf if candidate < first else -math.inf)
    return _num(first)


_WRITE_UNITS = {"wear coefficient": "mm^3/(N m)", "length": "mm", "volume": "mm^3",
                "force": "N", "density": "kg/m^3"}


# Significant digits of a manifest's numbers (parameters, uncertainties): the
# unit conversion and arithmetic leave last-digit noise in a float (5.05e-4
# mm^3/(N m) from 5.05e-13 1/Pa reads 0.0005050000000000001; 9.533 - 9.5 mm
# reads 0.032999999999999474); 12 digits drop it and keep 1e-12 of the value,
# far below any parameter's uncertainty.  The series' data keep round-trip digits.
MANIFEST_DIGITS = 12


def _manifest_num(value: float) -> str:
    """A manifest's number to `MANIFEST_DIGITS` significant digits, shortest form."""
    value = float(value)
    return _num(float(f"{value:.{MANIFEST_DIGITS}g}")) if math.isfinite(value) else _num(value)


def _quantity_text(value: float, dimension: str) -> str:
    """``"<number> <unit>"`` of an SI value (scaled by the unit's exact factor),
    to `MANIFEST_DIGITS` significant digits."""
    unit = _WRITE_UNITS[dimension]
    u = units.DIMENSIONS[dimension].units[unit]
    return _toml_string(f"{_manifest_num(float(_in_unit(value, u.scale)))} {unit}")


def _rule_holdout(s: Series, holdout_from: float | None) -> np.ndarray:
    if holdout_from is None:
        return np.zeros(s.x.shape, bool)
    return s.cycle_counts >= holdout_from


def _manifest_text(name, description, preset, parameters, series, bushing_density,
                   holdout_from_cycles) -> str:
    lines = ["# measured wear data (diffwear.calibrate format: the docs, 'Dataset format')",
             "[dataset]", f"name = {_toml_string(name)}"]
    if description:
        lines.append(f"description = {_toml_string(description)}")
    lines += ["", "[rig]", f"preset = {_toml_string(preset)}"]
    if bushing_density is not None:
        lines.append(f"bushing_density = {_quantity_text(bushing_density, 'density')}")
    lines += ["", "[parameters]"]
    for key, p in parameters.items():
        if key not in PARAMETERS or p.name != key:
            raise InputError(f"write_dataset: parameters[{key!r}]: unknown name or name "
                             f"mismatch ({p.name!r}); allowed: {PARAMETER_RULE}")
        dimension = PARAMETERS[key]
        def text(v, d: str | None = dimension) -> str:
            return _manifest_num(v) if d is None else _quantity_text(v, d)
        items = [] if p.value is None else [f"value = {text(p.value)}"]
        if p.std is not None:
            items.append(f"std = {text(p.std)}")
        if p.fit:
            items.append("fit = true")
        if not p.suspect:
            items.append("suspect = false")
        lines.append(f"{key} = {{ {', '.join(items)} }}")
    if holdout_from_cycles is not None:
        lines += ["", "[calibration]", f"holdout_from_cycles = {_num(holdout_from_cycles)}"]
    for s in series:
        spec = KINDS[s.kind]
        lines += ["", "[[series]]", f"kind = {_toml_string(s.kind)}",
                  f"file = {_toml_string(s.file.as_posix())}"]
        if s.name != s.file.stem:
            lines.append(f"name = {_toml_string(s.name)}")
        if spec.cycles_key:
            lines.append(f"cycles = {_num(s.cycles)}")
        lines.append(f"uncertainty = {_quantity_text(s.sigma, spec.quantity)}")
        if s.kind == "volume":
            lines.append(f"basis = {_toml_string(s.basis)}")
        rule = _rule_holdout(s, holdout_from_cycles)
        if not np.array_equal(s.holdout, rule):
            lines.append(f"role = {_toml_string('holdout' if s.holdout.all() else 'fit')}")
    return "\n".join(lines) + "\n"


def _csv_text(s: Series) -> str:
    spec = KINDS[s.kind]
    x_col, y_col = spec.write
    u = units.DIMENSIONS[spec.quantity].units[spec.write_unit]
    rows = [f"# {s.kind} series {s.name}: {x_col} [{'cycles' if x_col == 'cycles' else 'rad'}], "
            f"{y_col} [{spec.write_unit}]", f"{x_col},{y_col}"]
    rows += [f"{_num(x)},{_in_unit(y, u.scale)}" for x, y in zip(s.x, s.y)]
    return "\n".join(rows) + "\n"


def _check_series_to_write(series: Sequence[Series], holdout_from: float | None):
    files: dict[str, str] = {}
    for k, s in enumerate(series):
        where = f"write_dataset: series[{k}] ({s.name!r})"
        if s.kind not in KINDS:
            raise InputError(f"{where}: unknown kind {s.kind!r}; allowed: "
                             f"{', '.join(KINDS)}")
        spec = KINDS[s.kind]
        if s.x.shape != s.y.shape or s.holdout.shape != s.x.shape:
            raise InputError(f"{where}: x, y and holdout have shapes {s.x.shape}, {s.y.shape}, "
                             f"{s.holdout.shape}; allowed: equal lengths")
        if spec.cycles_key == (s.cycles is None):
            need = "a cycle count" if spec.cycles_key else "cycles = None (x holds the counts)"
            raise InputError(f"{where}: cycles = {s.cycles!r}; allowed: {need}")
        if s.kind == "volume" and s.basis not in BASES:
            raise InputError(f"{where}: basis = {s.basis!r}; allowed: {', '.join(BASES)}")
        if s.kind != "volume" and s.basis is not None:
            raise InputError(f"{where}: basis = {s.basis!r}; allowed: None (volume series only)")
        rel = s.file
        if rel.is_absolute() or ".." in rel.parts or not rel.parts or rel.suffix != ".csv":
            raise InputError(f"{where}: file {str(rel)!r}; allowed: a relative path inside the "
                             "folder ending in .csv, e.g. 'profile_02000.csv'")
        if rel.as_posix() == MANIFEST or rel.as_posix() in files:
            raise InputError(f"{where}: file {str(rel)!r} is already used by "
                             f"{files.get(rel.as_posix(), 'the manifest')}; allowed: one file "
                             "per series")
        files[rel.as_posix()] = f"series[{k}]"
        rule = _rule_holdout(s, holdout_from)
        if not (np.array_equal(s.holdout, rule) or s.holdout.all() or not s.holdout.any()):
            raise InputError(f"{where}: holdout marks {int(s.holdout.sum())} of {s.x.size} "
                             "points, which neither role nor holdout_from_cycles can express; "
                             "allowed: all points, no points, or those with cycles >= "
                             "holdout_from_cycles")


def write_dataset(folder: str | Path, *, name: str, parameters: Mapping[str, Parameter],
                  series: Sequence[Series], description: str = "", preset: str = "rig",
                  bushing_density: float | None = None,
                  holdout_from_cycles: float | None = None,
                  overwrite: bool = False) -> Dataset:
    """Write ``dataset.toml`` and one CSV per series (``Series.file``, relative
    to ``folder``) in the documented format; return the dataset loaded back.

    Values are written in mm, mm^3, N, rad and cycles: the series' data with
    round-trip digits (`repr`), so loading gives the SI values back to ~1
    ulp; the manifest's parameters and uncertainties to 12 significant digits
    (`MANIFEST_DIGITS`: 5.05e-4 mm^3/(N m), not the conversion's
    0.0005050000000000001).  Volume series are
    written as ``volume_mm3`` with their ``basis``.  Per-point ``holdout`` is
    written as the series' ``role`` or left to ``holdout_from_cycles``; anything
    else is refused.  Everything is checked (by loading a copy in a temporary
    folder) before ``folder`` is touched.  An existing non-empty ``folder`` is
    refused unless ``overwrite=True``, which replaces files of the same names
    and leaves other files there.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"{folder}: exists and is not a folder; allowed: a new or empty folder")
    if folder.is_dir() and not overwrite:
        entries = sorted(p.name for p in folder.iterdir())
        if entries:
            raise InputError(f"{folder}: the folder is not empty ({len(entries)} entries, e.g. "
                             f"{entries[0]!r}); allowed: a new or empty folder, or "
                             "overwrite=True to replace the files of the same names")
    series = list(series)
    _check_series_to_write(series, holdout_from_cycles)
    files = {MANIFEST: _manifest_text(name, description, preset, dict(parameters), series,
                                      bushing_density, holdout_from_cycles)}
    files.update({s.file.as_posix(): _csv_text(s) for s in series})

    with tempfile.TemporaryDirectory(prefix="diffwear-dataset-") as tmp:
        _write_files(Path(tmp), files)
        try:
            load_dataset(tmp)
        except InputError as err:
            message = str(err).replace(str(Path(tmp)), str(folder))
            raise InputError(f"write_dataset({folder}): the data would not load back: "
                             f"{message}") from None
    _write_files(folder, files)
    return load_dataset(folder)


def _write_files(folder: Path, files: Mapping[str, str]) -> None:
    for rel, text in files.items():
        target = folder / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(text, encoding="utf-8")
