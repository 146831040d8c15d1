"""Life maps of the two-joint design: each joint's life over its own (d, h).

`life_maps` evaluates a life model on a grid over the Table 8-3 box, one
joint's diameter and depth varied, the other joint held at a design (thesis
Figs. 8-7 and 8-8); `map_batch` compiles the grid's evaluation beforehand;
`map_trend` reads the thesis's trend ("life rises strongly with depth and
falls weakly with diameter") off the maps.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from .two_joint import LOWER, UPPER, TwoJointLife


def map_batch(model: TwoJointLife, points: int):
    """The compiled evaluation of a life map: the lives of ``points``^2 designs
    in one call.

    **Arguments:**

    - ``model``: the life model (a `TwoJointLife`, or one with its call and
      ``exact_gradients``).
    - ``points``: grid points per variable.

    **Returns:** the compiled function from designs (``points``^2, 4) to lives
    (``points``^2, 2) [cycles]: vmapped for a model with exact gradients (the
    quasi-static model, few scan slots), ``lax.map`` otherwise (the dynamic
    model: under vmap its scan's ``lax.cond`` becomes a select and every point
    runs all 3 x steps + 4 slots; docs/notes/design-solver.md).
    """
    if getattr(model, "exact_gradients", False):
        batch = jax.jit(jax.vmap(lambda x: model(x)))
    else:
        batch = jax.jit(lambda xs: jax.lax.map(model, xs))
    return batch.lower(jax.ShapeDtypeStruct((points * points, 4), jnp.float64)).compile()


def life_maps(model: TwoJointLife, x, points: int, batch=None) -> dict:
    """Each joint's life over its own diameter and depth, the other joint at ``x``
    (thesis Figs. 8-7 and 8-8).

    **Arguments:**

    - ``model``: the life model.
    - ``x``: the design (d1, d2, h1, h2) [m] at which the other joint is held.
    - ``points``: grid points per variable, spanning the Table 8-3 box.
    - ``batch``: `map_batch` of ``model`` and ``points``, compiled beforehand
      (compiled here when None).

    **Returns:** {"d_m": (points,), "h_m": (points,), "cyc1": (points, points),
    "cyc2": (points, points)}: the grid [m] and joint j's life [cycles] over
    [d_j, h_j], one compiled call per joint.
    """
    d = np.linspace(LOWER[0], UPPER[0], points)
    h = np.linspace(LOWER[2], UPPER[2], points)
    dd, hh = np.meshgrid(d, h, indexing="ij")
    batch = map_batch(model, points) if batch is None else batch
    maps = {"d_m": d, "h_m": h}
    for j in (0, 1):
        xs = np.repeat(np.asarray(x)[None], dd.size, axis=0)
        xs[:, j], xs[:, j + 2] = dd.ravel(), hh.ravel()
        maps[f"cyc{j + 1}"] = np.asarray(batch(jnp.asarray(xs)))[:, j].reshape(dd.shape)
    return maps


def map_trend(maps: dict) -> dict:
    """The thesis's trend check read off the life maps (Figs. 8-7 and 8-8: life
    "rises strongly with depth and falls weakly with diameter").

    Read over the whole Table 8-3 box rather than from a local derivative: at
    the default cycle tolerance the model's life carries ~3e-4 relative
    noise, which central differences at 1e-3 relative step turn into ~400
    cycles/mm, more than the diameter slope itself (measured on the coarse
    model).

    **Arguments:**

    - ``maps``: `life_maps`'s result (only ``cyc1`` and ``cyc2`` are read).

    **Returns:** per joint (lists over joints 1, 2): ``depth_life_ratio`` (life at
    the deepest over the shallowest bushing, least over the diameters),
    ``diameter_relative_change`` (life at the largest minus the smallest
    diameter, over their mean, the extreme over the depths),
    ``rises_with_depth`` and ``falls_with_diameter`` (every grid line
    monotone); and ``life_rises_with_depth``, ``life_falls_with_diameter``
    (for both joints).
    """
    out: dict[str, Any] = {"rises_with_depth": [], "falls_with_diameter": [],
                           "depth_life_ratio": [], "diameter_relative_change": []}
    for j in (1, 2):
        c = maps[f"cyc{j}"]  # [d, h]
        out["rises_with_depth"].append(bool(np.all(np.diff(c, axis=1) > 0)))
        out["falls_with_diameter"].append(bool(np.all(np.diff(c, axis=0) < 0)))
        out["depth_life_ratio"].append(float(np.min(c[:, -1] / c[:, 0])))
        change = (c[-1] - c[0]) / (0.5 * (c[-1] + c[0]))
        out["diameter_relative_change"].append(float(change[np.argmax(np.abs(change))]))
    out["life_rises_with_depth"] = all(out["rises_with_depth"])
    out["life_falls_with_diameter"] = all(out["falls_with_diameter"])
    return out
