"""Calibrating a user's mechanism file: its numbers as parameters.

A dataset may name a mechanism file (``[rig] mechanism = "linkage.toml"``)
instead of the preset rig.  Any number in that file is a parameter, named by
its path: ``"<section>.<element name>.<key>"`` with nested keys and vector
components, e.g. ``"bodies.rod.mass"``, ``"forces.slider_spring.free_length"``,
``"joints.crank_rod.wear.coefficient"``, ``"joints.crank_rod.pin_point[0]"``.

How a file number reaches the model (traced, so it differentiates): the file
is loaded three times, as written and with the number moved by +-1e-3 of
itself; each leaf of the mechanism (and of the assembly guess) that moves
gets the map its three values fit exactly: affine, p = p0 + (v - v0) dp/dv
(masses, points, spring rates, clearances), or a power law, p = p0 (v /
v0)^a (a layer thickness setting a stiffness E / L: a = -1; a mass setting a
damping time: a = 1/2).  A number whose leaves follow neither is refused with
the reason.

The wearing joint is the file's clearance joint with a wear law (``[rig]
joint`` names it when there are several); its cycle is that of
`diffwear.mechanism_file.wear.drive`.
"""

from __future__ import annotations

import copy
import math
import re
import tomllib
from pathlib import Path
from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..config import MechanismFile, load_dict, units
from ..contact import centred_state
from ..dynamics import consistent_state
from ..errors import InputError
from ..mechanism_file.wear import drive, drive_period, wearing_joints
from ..quasistatic.loads import ideal_parent
from .effects import EffectValues, wear_law
from .quasi_static import QuasiStaticRigHistory

_STEP = 1e-3        # relative move of a number to find its map onto the model
_LINEAR_TOL = 1e-7  # the two one-sided maps must agree to this (a 1/L leaf: 2e-3)
_PATH = re.compile(r"(?P<key>[^.\[\]]+)(?:\[(?P<index>\d+)\])?")


def _locate(doc: dict, path: str, file: str):
    """(container, key) of the number at ``path`` in the parsed file."""
    parts = path.split(".")
    if len(parts) < 3 or parts[0] not in ("bodies", "joints", "forces"):
        raise InputError(f"{file}: parameter {path!r}: a path '<bodies|joints|forces>.<element "
                         "name>.<key>', e.g. 'bodies.rod.mass' or 'joints.crank_rod.pin_point[0]'")
    section, name = parts[0], parts[1]
    items = [t for t in doc.get(section, []) if isinstance(t, dict) and t.get("name") == name]
    if not items:
        names = [t.get("name") for t in doc.get(section, []) if isinstance(t, dict)]
        raise InputError(f"{file}: parameter {path!r}: no [[{section}]] named {name!r}; "
                         f"allowed: {', '.join(map(str, names)) or '(none)'}")
    node = items[0]
    key: str | int | None = None
    for k, part in enumerate(parts[2:]):
        m = _PATH.fullmatch(part)
        if m is None or not isinstance(node, dict) or m["key"] not in node:
            have = ", ".join(node) if isinstance(node, dict) else "(not a table)"
            raise InputError(f"{file}: parameter {path!r}: no key {part!r}; allowed: {have}")
        if k < len(parts) - 3:
            node = node[m["key"]]
            if m["index"] is not None:
                node = node[int(m["index"])]
            continue
        if m["index"] is not None:
            node, key = node[m["key"]], int(m["index"])
        else:
            key = m["key"]
    value = node[key] if isinstance(node, (dict, list)) else None
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise InputError(f"{file}: parameter {path!r} is not a number (got {value!r})")
    return node, key


def file_value(doc: dict, path: str, file: str) -> tuple[float, str | None]:
    """(SI value, dimension or None for a plain number) of the number at ``path``."""
    node, key = _locate(doc, path, file)
    raw = node[key]
    if isinstance(raw, str):
        m = units._QUANTITY.fullmatch(raw)
        dim = units._dimension_of(units.normalise_unit(m["unit"])) if m else None
        if dim is None:
            raise InputError(f"{file}: parameter {path!r}: {raw!r} is not a number with a "
                             "known unit")
        return units.parse_quantity(raw, dim), dim
    return float(raw), None


def _moved(doc: dict, path: str, file: str, factor: float) -> dict:
    out = copy.deepcopy(doc)
    node, key = _locate(out, path, file)
    raw = node[key]
    if isinstance(raw, str):
        m = units._QUANTITY.fullmatch(raw)
        assert m is not None  # the file loaded, so each of its quantities parses
        node[key] = f"{float(m['num']) * factor!r} {m['unit']}"
    else:
        node[key] = float(raw) * factor
    return out


def _leaves(study):
    return jax.tree.leaves((study.mechanism, study.q_guess))


def _leaf_map(a, b, c, v0, name, file):
    """("affine", dp/dv) or ("power", exponent) of a leaf at a, b, c (the
    number at v0, v0 (1 + h), v0 (1 - h)); refused if neither fits."""
    plus, minus = (b - a) / (_STEP * v0), (a - c) / (_STEP * v0)
    size = max(float(np.max(np.abs(plus))), 1e-300)
    if np.max(np.abs(plus - minus)) <= _LINEAR_TOL * size:
        return "affine", 0.5 * (plus + minus)
    with np.errstate(divide="ignore", invalid="ignore"):
        up = np.log(b / a) / math.log1p(_STEP)
        down = np.log(c / a) / math.log1p(-_STEP)
    if np.all(np.isfinite(up)) and np.allclose(up, down, rtol=0.0, atol=1e-6):
        return "power", 0.5 * (up + down)
    raise InputError(
        f"{file}: parameter {name!r} enters the model neither linearly nor as a power law; "
        "allowed: a number the model depends on like a mass, length, point, stiffness, "
        "layer thickness (E / L), spring rate or wear coefficient")


class FileParameterMap(eqx.Module):
    """The exact linear maps of a file's numbers onto the model's leaves
    (module notes): ``value0[name]`` (SI) and, per name, the moving leaves'
    indices and derivatives."""

    names: tuple = eqx.field(static=True)
    value0: dict
    moves: dict

    @classmethod
    def build(cls, doc: dict, names, file: str, study) -> "FileParameterMap":
        base = _leaves(study)
        value0, moves = {}, {}
        for name in names:
            v0, _ = file_value(doc, name, file)
            if v0 == 0.0:
                raise InputError(f"{file}: parameter {name!r} is 0 in the file: a parameter is "
                                 "fitted on a log scale and must be non-zero")
            up = _leaves(load_dict(_moved(doc, name, file, 1 + _STEP), file=file))
            down = _leaves(load_dict(_moved(doc, name, file, 1 - _STEP), file=file))
            found = []
            for i, (a, b, c) in enumerate(zip(base, up, down)):
                a, b, c = (np.asarray(x, dtype=float) for x in (a, b, c))
                if a.shape != b.shape or np.array_equal(a, b) and np.array_equal(a, c):
                    continue
                found.append((i, *_leaf_map(a, b, c, v0, name, file)))
            if not found:
                raise InputError(f"{file}: parameter {name!r} does not change the model")
            value0[name] = v0
            moves[name] = tuple((i, kind, jnp.asarray(coef)) for i, kind, coef in found)
        return cls(tuple(names), value0, moves)

    def apply(self, study, values: dict):
        """(mechanism, assembly guess) at ``values`` (SI, any subset of names)."""
        leaves = list(_leaves(study))
        for name in self.names:
            if name not in values:
                continue
            v, v0 = values[name], self.value0[name]
            for i, kind, coef in self.moves[name]:
                leaf = jnp.asarray(leaves[i], dtype=float)
                if kind == "affine":
                    leaves[i] = leaf + (v - v0) * coef
                else:  # power law: leaf0 (v / v0)^a
                    leaves[i] = leaf * jnp.exp(coef * jnp.log(v / v0))
        treedef = jax.tree.structure((study.mechanism, study.q_guess))
        return jax.tree.unflatten(treedef, leaves)


def wearing_joint(study, joint: str | None, file: str) -> str:
    """The clearance joint with a wear law (``joint`` if given)."""
    found = wearing_joints(study)
    if joint is not None:
        if joint not in found:
            raise InputError(f"{file}: joint {joint!r} is not a clearance joint with a wear law; "
                             f"allowed: {', '.join(found)}")
        return joint
    if len(found) != 1:
        raise InputError(f"{file}: {len(found)} clearance joints with a wear law "
                         f"({', '.join(found)}); allowed: exactly one, or name it "
                         "in [rig] joint = \"...\"")
    return found[0]


def load_file(path: Path):
    """(parsed TOML, `MechanismFile`) of a mechanism file."""
    from ..config import load

    study = load(path)
    return tomllib.loads(Path(path).read_text(encoding="utf-8")), study


class QuasiStaticFileHistory(QuasiStaticRigHistory):
    """`QuasiStaticRigHistory` on a mechanism file's wearing joint: ``base``
    holds the file parameters by path (`FileParameterMap`); the effects' wear
    law replaces the joint's (guide friction does not apply)."""

    study: object = None
    parameters: FileParameterMap | None = None
    joint_name: str = eqx.field(static=True, default="")
    file_period: float = eqx.field(static=True, default=1.0)

    # the dynamic check is the rig's dynamic model: not a user's mechanism
    checked_on_dynamic: ClassVar[bool] = False

    @property
    def period(self) -> float:
        return self.file_period

    @property
    def joint(self) -> str:
        return self.joint_name

    @property
    def file_study(self) -> MechanismFile:
        assert isinstance(self.study, MechanismFile)  # set by `file_model`
        return self.study

    @property
    def file_parameters(self) -> FileParameterMap:
        assert self.parameters is not None  # set by `file_model`
        return self.parameters

    def describe(self) -> str:
        return (super().describe() + f"; mechanism file {self.file_study.file}, joint "
                f"{self.joint_name!r}")

    def mechanism(self, base: dict, effects: EffectValues):
        mech, q_guess = self.file_parameters.apply(self.file_study, base)
        index = next(i for i, f in enumerate(mech.forces) if f.name == self.joint_name)
        k = mech.forces[index].wear.coefficient
        mech = eqx.tree_at(lambda m: m.forces[index].wear, mech, wear_law(k, effects))
        ideal = ideal_parent(mech)
        y0 = centred_state(ideal, consistent_state(ideal, q_guess, check=False), mech)
        return mech, y0

    def crank_angle(self, mech, y0):
        d = drive(self.study)
        return mech.frames(mech.split(y0)[0]).pose(d.body)[2]


def file_model(path: Path, names, joint: str | None, **settings) -> QuasiStaticFileHistory:
    doc, study = load_file(path)
    file = str(path)
    name = wearing_joint(study, joint, file)
    params = FileParameterMap.build(doc, names, file, study)
    return QuasiStaticFileHistory(study=study, parameters=params, joint_name=name,
                                  file_period=drive_period(study), **settings)
