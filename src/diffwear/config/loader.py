"""Read a mechanism file (TOML, stdlib `tomllib`) into a `MechanismFile`.

Top level (see the docs, "Mechanism files"):

    title, source         optional strings, shown in the report
    [[bodies]]            name, mass, inertia
    [[joints]]            type = one of JOINT_TYPES, then that type's fields
    [[forces]]            type = one of FORCE_TYPES, then that type's fields
    [initial]             <body> = { x, y, phi }: assembly guess for every body
    [simulation]          duration, n_save, rtol, atol, baumgarte_alpha/beta, max_steps
    [outputs]             reactions = ["joint", { joint = "...", on = "body" }, ...],
                          contact = ["<clearance joint>", ...]

A ``[[joints]]`` entry may build a force element (``type = "clearance"``): it
joins the mechanism's forces (after those of ``[[forces]]``), and the study's
``assembly`` mechanism holds the ideal joint that stands in for it at t = 0.

Every problem raises `InputError("<file>: <key path>: <what>; allowed: ...")`.
Nothing here integrates or assembles; see `diffwear.cli.run`.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from pathlib import Path

import jax.numpy as jnp

from ..choices import SHIPPED_MECHANISMS, shipped_mechanism_names
from ..errors import InputError
from ..mechanism import GROUND, AbstractForceElement, Body, Mechanism
from .elements import FORCE_TYPES, JOINT_TYPES, ElementType, FieldError
from .mechanism_file import (
    DEFAULT_ALPHA,
    DEFAULT_ATOL,
    DEFAULT_BETA,
    DEFAULT_MAX_STEPS,
    DEFAULT_N_SAVE,
    DEFAULT_RTOL,
    ContactOutput,
    MechanismFile,
    ReactionOutput,
    Simulation,
)
from .schema import (
    NAME_RULE,
    Context,
    Integer,
    Number,
    Quantity,
    Text,
    check_table,
    check_unknown,
    read_array_of_tables,
    read_table,
    read_type_tag,
    show,
    suggest,
    toml_type,
)

SECTIONS = ("title", "source", "bodies", "joints", "forces", "initial", "simulation", "outputs")

BODY_FIELDS = {
    "name": Text(name=True),
    "mass": Quantity(dimension="mass", low=0.0, low_open=True),
    "inertia": Quantity(dimension="inertia", low=0.0, low_open=True, doc="about the COM"),
}

POSE_FIELDS = {
    "x": Quantity(dimension="length"),
    "y": Quantity(dimension="length"),
    "phi": Quantity(dimension="angle"),
}

# Sanity bounds: beyond them a value is a typo, not a study.
MAX_DURATION = 1e5  # s (~28 h of simulated time)
MAX_N_SAVE = 10**7  # saved states (memory: n_save x state size x 8 bytes)
SIMULATION_FIELDS = {
    "duration": Quantity(dimension="time", low=0.0, low_open=True, high=MAX_DURATION),
    "n_save": Integer(default=DEFAULT_N_SAVE, low=2, high=MAX_N_SAVE),
    # float64 epsilon is 2.2e-16: a relative tolerance below ~1e-14 cannot be met.
    "rtol": Number(default=DEFAULT_RTOL, low=1e-14, high=0.1),
    "atol": Number(default=DEFAULT_ATOL, low=1e-16, high=1.0),
    # Gains above 1e5 1/s make the stabilised DAE stiffer than any step size allows.
    "baumgarte_alpha": Quantity(dimension="rate", default=DEFAULT_ALPHA, low=0.0, high=1e5),
    "baumgarte_beta": Quantity(dimension="rate", default=DEFAULT_BETA, low=0.0, high=1e5),
    "max_steps": Integer(default=DEFAULT_MAX_STEPS, low=1, high=10**9),
}

REACTION_FIELDS = {"joint": Text(), "on": Text(default=None)}
OUTPUT_KEYS = ("reactions", "contact")


# ----------------------------------------------------------------------------- entry points
def shipped_mechanisms() -> dict[str, Path]:
    """Name -> path of each mechanism file shipped with the package (the
    thesis's mechanisms and an example), loadable by name: ``load("rig")``,
    ``diffwear run rig``."""
    return {name: SHIPPED_MECHANISMS / f"{name}.toml" for name in shipped_mechanism_names()}


def resolve(path: str | Path) -> Path:
    """``path``, or the shipped mechanism file of that name when ``path`` is a
    bare name (no folder, no suffix) that is not a file here."""
    candidate = Path(path)
    shipped = shipped_mechanisms()
    if (not candidate.exists() and candidate.suffix == "" and candidate.name == str(path)
            and candidate.name in shipped):
        return shipped[candidate.name]
    return candidate


def load(path: str | Path) -> MechanismFile:
    """Load a mechanism file (a path, or the name of a shipped one:
    `shipped_mechanisms`); raise `InputError` naming the file for any problem."""
    path = resolve(path)
    data = read_input(path, "a path to a .toml mechanism file, or a shipped mechanism: "
                      + ", ".join(shipped_mechanisms()))
    return loads(data, file=str(path))


def read_input(path: Path, allowed: str) -> bytes:
    """The bytes of an input file; `InputError` naming it (and what is
    ``allowed``) when it is missing, a directory or unreadable."""
    file = str(path)
    try:
        return Path(path).read_bytes()
    except FileNotFoundError:
        raise InputError(f"{file}: no such file; allowed: {allowed}") from None
    except IsADirectoryError:
        raise InputError(f"{file}: is a directory, not a file; allowed: {allowed}") from None
    except OSError as err:
        raise InputError(f"{file}: cannot be read ({err.strerror})") from None


def decode(data: bytes, file: str, note: str = "TOML files are UTF-8") -> str:
    """UTF-8 text of ``data`` (a leading byte-order mark is dropped); ``note`` ends
    the error message's "allowed" part."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as err:
        line = data[: err.start].count(b"\n") + 1
        raise InputError(
            f"{file}: line {line}: byte {err.start} ({data[err.start:err.start + 1]!r}) is not "
            f"UTF-8 ({err.reason}); allowed: UTF-8 text ({note})"
        ) from None
    return text.removeprefix("\ufeff")


def loads(source: str | bytes, file: str = "<string>") -> MechanismFile:
    """Load mechanism-file text (``file`` names it in messages)."""
    text = decode(source, file) if isinstance(source, bytes) else source
    if not text.strip():
        raise InputError(f"{file}: the file is empty; allowed: a TOML mechanism description "
                         "with [[bodies]], [initial] and [simulation]")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise InputError(f"{file}: invalid TOML: {err}; allowed: TOML 1.0 syntax "
                         "(https://toml.io)") from None
    return load_dict(data, file=file)


def load_dict(data: Mapping, file: str = "<dict>") -> MechanismFile:
    """Build a `MechanismFile` from parsed TOML (a dict of dicts, lists and scalars)."""
    ctx = Context(file)
    if not isinstance(data, Mapping):
        raise ctx.error("(top level)", f"expected a table, got {toml_type(data)}")
    if not data:
        raise InputError(f"{file}: the file holds no keys or tables (only comments?); allowed: "
                         "[[bodies]], [[joints]], [[forces]], [initial], [simulation], [outputs]")
    check_unknown(ctx, "", data, SECTIONS)
    title = _optional_text(ctx, data, "title")
    source = _optional_text(ctx, data, "source")

    bodies = _bodies(ctx, data.get("bodies"))
    ctx.bodies = tuple(b.name for b in bodies)
    by_name = {b.name: b for b in bodies}
    joints = _elements(ctx, "joints", data.get("joints"), JOINT_TYPES, FORCE_TYPES, by_name)
    forces = _elements(ctx, "forces", data.get("forces"), FORCE_TYPES, JOINT_TYPES, by_name)
    _unique_element_names(ctx, data, [(k, e) for k, e, *_ in joints],
                          [(k, e) for k, e, *_ in forces])
    # joints that are force elements (clearance joints) go after the [[forces]]
    floating = [e for _, e, *_ in joints if isinstance(e, AbstractForceElement)]
    constraints = [e for _, e, *_ in joints if not isinstance(e, AbstractForceElement)]
    plain_forces = [e for _, e, *_ in forces]
    try:
        mechanism = Mechanism(bodies, constraints, [*plain_forces, *floating])
        assembly = None
        if floating:
            stand_in = [spec.assembly(e) if isinstance(e, AbstractForceElement) else e
                        for _, e, spec, _ in joints]
            assembly = Mechanism(bodies, stand_in, plain_forces)
    except InputError as err:  # checks above should catch everything; keep the file name
        raise InputError(f"{file}: {err}") from None
    reactions, contacts = _outputs(ctx, data.get("outputs", {}), mechanism)

    return MechanismFile(
        file=file,
        title=title,
        source=source,
        mechanism=mechanism,
        q_guess=_initial(ctx, data.get("initial")),
        simulation=_simulation(ctx, data.get("simulation")),
        reactions=reactions,
        contacts=contacts,
        assembly=assembly,
        bushing_walls=tuple((e.name, float(v["law"]["layer_thickness"]))
                            for _, e, _, v in joints
                            if isinstance(v.get("law"), Mapping)
                            and v["law"].get("layer_thickness") is not None),
    )


# ----------------------------------------------------------------------------- sections
def _optional_text(ctx, data, key) -> str:
    value = data.get(key, "")
    if not isinstance(value, str):
        raise ctx.error(key, f"expected a string, got {toml_type(value)} {show(value)}", "a string")
    return value


def _bodies(ctx: Context, raw) -> list[Body]:
    out: list[Body] = []
    seen: dict[str, int] = {}
    for k, table in enumerate(read_array_of_tables(ctx, "bodies", raw, required=True)):
        v = read_table(ctx, f"bodies[{k}]", table, BODY_FIELDS)
        name = v["name"]
        if name == GROUND:
            raise ctx.error(f"bodies[{k}].name", f"{GROUND!r} is reserved for the fixed frame",
                            f"any other name: {NAME_RULE}")
        if name in seen:
            raise ctx.error(f"bodies[{k}].name",
                            f"{name!r} is already the name of bodies[{seen[name]}]",
                            "unique body names")
        seen[name] = k
        try:
            out.append(Body(name, v["mass"], v["inertia"]))
        except InputError as err:
            raise ctx.wrap(f"bodies[{k}].inertia", err) from None
    return out


def _elements(ctx: Context, section: str, raw, types: Mapping[str, ElementType],
              other: Mapping[str, ElementType], bodies: Mapping[str, Body]):
    """[(index, element, its ElementType, its parsed values)] of ``[[joints]]``
    or ``[[forces]]``."""
    out = []
    home = "forces" if section == "joints" else "joints"
    for k, table in enumerate(read_array_of_tables(ctx, section, raw, required=False)):
        path = f"{section}[{k}]"
        kind = table.get("type")
        in_other = isinstance(kind, str) and kind in other
        hint = f" ({kind!r} belongs under [[{home}]])" if in_other else ""
        kind = read_type_tag(ctx, path, table, types, f"{section[:-1]} type", hint)
        spec = types[kind]
        values = read_table(ctx, path, {key: val for key, val in table.items() if key != "type"},
                            spec.fields)
        try:
            element = spec.build(values, bodies) if spec.bodies else spec.build(values)
        except FieldError as err:
            raise ctx.error(f"{path}.{err.key}", err.what, err.allowed) from None
        except InputError as err:
            raise ctx.wrap(path, err) from None
        if (isinstance(element, AbstractForceElement) and section == "joints"
                and spec.assembly is None):
            raise TypeError(f"joint type {kind!r} builds a force element but has no assembly")
        names = element.bodies
        if len(set(names)) < len(names):
            raise ctx.error(path, f"connects body {names[0]!r} to itself",
                            "two different bodies (one may be \"ground\")")
        out.append((k, element, spec, values))
    return out


def _unique_element_names(ctx, data, constraints, forces):
    seen = {}
    for section, items in (("joints", constraints), ("forces", forces)):
        for k, element in items:
            path = f"{section}[{k}]"
            if element.name in seen:
                raise ctx.error(f"{path}.name",
                                f"{element.name!r} is already the name of {seen[element.name]}",
                                "names unique among all joints and forces")
            seen[element.name] = path


def _initial(ctx: Context, raw):
    if raw is None:
        raise ctx.error("initial", "missing section",
                        "[initial] with <body> = { x = \"..\", y = \"..\", phi = \"..\" } "
                        "for every body")
    table = check_table(ctx, "initial", raw, "<body> = { x, y, phi } for every body")
    check_unknown(ctx, "initial", table, ctx.bodies)
    rows = []
    for name in ctx.bodies:
        if name not in table:
            raise ctx.error(f"initial.{name}", "missing guess for this body",
                            f"{name} = {{ x = \"0 m\", y = \"0 m\", phi = \"0 deg\" }}")
        v = read_table(ctx, f"initial.{name}", table[name], POSE_FIELDS, "{ x, y, phi }")
        rows += [v["x"], v["y"], v["phi"]]
    return jnp.asarray(rows, dtype=float)


def _simulation(ctx: Context, raw) -> Simulation:
    if raw is None:
        raise ctx.error("simulation", "missing section",
                        "[simulation] with at least duration = \"2 s\"")
    v = read_table(ctx, "simulation", raw, SIMULATION_FIELDS)
    return Simulation(**v)


def _outputs(ctx: Context, raw, mechanism: Mechanism):
    table = check_table(ctx, "outputs", raw, "reactions = [...], contact = [...]")
    check_unknown(ctx, "outputs", table, OUTPUT_KEYS)
    return _reactions(ctx, table, mechanism), _contacts(ctx, table, mechanism)


def _clearance_names(mechanism: Mechanism) -> list[str]:
    from ..contact import ClearanceJoint

    return [f.name for f in mechanism.forces if isinstance(f, ClearanceJoint)]


def _contacts(ctx: Context, table, mechanism: Mechanism) -> tuple[ContactOutput, ...]:
    entries = table.get("contact", [])
    names = _clearance_names(mechanism)
    allowed = ", ".join(repr(n) for n in names) or "(no clearance joints)"
    if not isinstance(entries, list):
        raise ctx.error("outputs.contact", f"expected an array, got {toml_type(entries)} "
                        f"{show(entries)}", f"an array of clearance joint names: {allowed}")
    out: list[ContactOutput] = []
    for k, name in enumerate(entries):
        path = f"outputs.contact[{k}]"
        if not isinstance(name, str):
            raise ctx.error(path, f"expected a clearance joint name, got {toml_type(name)} "
                            f"{show(name)}", allowed)
        if name not in names:
            others = [c.name for c in mechanism.constraints] + [f.name for f in mechanism.forces]
            what = (f"{name!r} is not a clearance joint (it has no contact)" if name in others
                    else f"unknown clearance joint {name!r}{suggest(name, names)}")
            raise ctx.error(path, what, allowed)
        if name in (o.joint for o in out):  # one contact_<joint>.csv per joint
            raise ctx.error(path, f"joint {name!r} is requested twice", "each joint once")
        out.append(ContactOutput(name))
    return tuple(out)


def _reactions(ctx: Context, table, mechanism: Mechanism) -> tuple[ReactionOutput, ...]:
    entries = table.get("reactions", [])
    joints = {c.name: c for c in mechanism.constraints}
    if not isinstance(entries, list):
        raise ctx.error("outputs.reactions", f"expected an array, got {toml_type(entries)} "
                        f"{show(entries)}", "an array of joint names or { joint, on } tables")
    out, seen = [], set()
    for k, entry in enumerate(entries):
        path = f"outputs.reactions[{k}]"
        if isinstance(entry, str):
            entry = {"joint": entry}
        elif not isinstance(entry, dict):
            raise ctx.error(path, f"expected a joint name or a table, got {toml_type(entry)} "
                            f"{show(entry)}",
                            "\"<joint>\" or { joint = \"<joint>\", on = \"<body>\" }")
        v = read_table(ctx, path, entry, REACTION_FIELDS)
        name = v["joint"]
        if name not in joints:
            forces = [f.name for f in mechanism.forces]
            what = f"unknown joint {name!r}{suggest(name, list(joints))}"
            if name in forces:
                what = f"{name!r} is a force element, not a joint (it has no reaction)"
            if name in _clearance_names(mechanism):
                what = (f"{name!r} is a clearance joint: it has no reaction, request its "
                        f"contact force with contact = [{name!r}]")
            raise ctx.error(path, what, ", ".join(joints) or "(no joints)")
        movable = [b for b in joints[name].bodies if b != GROUND]
        on = movable[-1] if v["on"] is None else v["on"]
        if on not in movable:
            raise ctx.error(f"{path}.on", f"{on!r} is not a (non-ground) body of joint {name!r}",
                            ", ".join(movable))
        if name in seen:  # one reaction_<joint>.csv per joint
            raise ctx.error(path, f"joint {name!r} is requested twice", "each joint once")
        seen.add(name)
        out.append(ReactionOutput(name, on))
    return tuple(out)
