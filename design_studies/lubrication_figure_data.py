#!/usr/bin/env python3
"""Stored data of the lubricated joint's validation figures
(docs/guide/lubrication.md, drawn at build time by ``docs/figures.py``).

Writes into ``design_studies/results/studies/lubrication/`` (a few tens of kB):

* ``steady_films.csv``: the short- and long-bearing films (`ShortBearingFilm`,
  `LongBearingFilm` ``.film``) at steady states, eps = 0.05 .. 0.95: the load
  along and across the line of centres, to set against the closed forms of
  Hamrock, Schmid & Jacobson (short bearing; half-Sommerfeld long bearing);
* ``sommerfeld.csv``: the quasi-static equilibrium of a film-borne journal
  (`LubricatedQuasiStaticJoint.pin_offset`, roughness 1 nm, so the
  asperities never touch) under steady loads over five decades, and the
  short bearing's closed-form eps for each load;
* ``life_viscosity.json``: the Ch. 7 rig's crank-rod joint lubricated
  (`MixedLubrication(default_film(mu, depth, c, R, eps_max), foundation,
  0.4 um)`: the finite film, L/D = 0.69),
  its quasi-static life to 50 um against the viscosity, the dry life and the
  derivative d(life)/d(mu) by forward-mode autodiff (`jax.jvp`) at a few
  viscosities;
* ``slider_crank.csv``: the Table 2-1 slider-crank (c = 0.1 mm, EFM) with its
  crank-rod joint lubricated (sigma 1 um; `default_film`: the finite film,
  L/D = 0.32) at 0.5 and 0.02 Pa s, and dry, over
  one crank revolution on Rodas4 (rtol = atol = 1e-8): the pin's offset in
  the bushing over the clearance, the film parameter and the asperity load;
* ``four_bar_squeeze.csv``: the shipped four-bar (``four_bar_wear``) with
  its coupler-rocker joint in oil (sigma 1 um; the default film, finite at
  L/D = 0.83) at 0.5 and 0.005 Pa s, the
  quasi-static model's film over one cycle (360 samples): the journal's
  orbit with the squeeze film and the steady balance at every sample
  (``squeeze=False``), the minimum film and the relative rotation;
* ``rig/``: ``diffwear run rig_lubricated --cycles 21400`` (the shipped file):
  its ``summary.json`` (its ``file`` the repository path) and
  ``film_crank_rod.csv``;
* ``four_bar/``: ``diffwear run four_bar_lubricated --cycles 1000000 --limit
  0.05`` alike (``film_coupler_rocker.csv``);
* ``validity_map.csv``: the finite film's steady load (`reynolds_forces`,
  96 nodes round the bushing, at least 3 rows per radius along it) over
  L/D = 0.05 .. 20 and eps = 0.05 .. 0.99, in units of 6 mu omega R^4 / c^2,
  to set the short and long films' closed forms against (the validity map);
* ``raimondi_boyd.csv``: `FiniteBearingFilm` (default grid) at steady states,
  L/D = 1/4, 1/2, 1, eps = 0.05 .. 0.97: the Sommerfeld number and the
  attitude angle, to set against Raimondi & Boyd's table
  (`diffwear.contact.raimondi_boyd`).

    PYTHONPATH=src .venv/bin/python design_studies/lubrication_figure_data.py
    PYTHONPATH=src .venv/bin/python design_studies/lubrication_figure_data.py --only life rig
    PYTHONPATH=src .venv/bin/python design_studies/lubrication_figure_data.py \
        --only validity raimondi-boyd

Run time on the 2-core CPU, compiles included (measured part by part):
steady films 5 s, Sommerfeld 7 s, life against viscosity 7 min (14 lives
and 4 tangents on the finite film, another job on the cores), slider-crank
20 s, the four-bar's films 1 min, the rig run 4 min, the four-bar run
2 min; all ~15 min.
The finite film's parts, measured with the cores shared with other jobs: the
validity map 17 min (240 Reynolds solves, the larger L/D the slower),
Raimondi & Boyd 72 s.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STORE = ROOT / "design_studies" / "results" / "studies" / "lubrication"
SIGNIFICANT = 7

# the film-only checks (a, b): a connecting-rod-like pin, as tests/test_lubrication.py
# and tests/test_lubricated_joint.py: R = 10 mm, L = 8 mm (short, L/D = 0.4),
# c = 50 um, mu = 0.04 Pa s, omega = 100 rad/s; the long bearing L = 80 mm (L/D = 4)
MU, R, C, OMEGA = 0.04, 0.010, 50e-6, 100.0
L_SHORT, L_LONG = 0.008, 0.080
KF = 1e13  # PTFE-like foundation [Pa/m], as tests/test_lubricated_joint.py

# the rig's life against viscosity (c): the settings of tests/test_lubricated_joint.py
RIG_ROUGHNESS = 0.4e-6
RIG_LIMIT = 0.05e-3
RIG_STEPS, RIG_SAMPLES = 10, 60
# (the finite film: from a film that barely matters to one under which the
# joint runs in, from ~25 mPa s at sigma = 0.4 um; denser where the life climbs)
VISCOSITIES = [1e-5, 1e-4, 1e-3, 3e-3, 5e-3, 7e-3, 1e-2, 1.2e-2, 1.4e-2, 1.6e-2, 1.8e-2,
               2e-2, 2.5e-2, 3e-2]
TANGENTS_AT = [3e-3, 7e-3, 1e-2, 1.4e-2]

# the four-bar through its reversals (f): the oils of tests/test_squeeze_orbit.py,
# the shipped runs' 360 samples
FB_VISCOSITIES, FB_ROUGHNESS, FB_SAMPLES = [0.5, 0.005], "1 um", 360

# the lubricated slider-crank (d)
SC_CLEARANCE, SC_ROUGHNESS = 0.1e-3, 1e-6
SC_VISCOSITIES = [0.5, 0.02]

# the validity map (f): L/D from a short to a long bearing, 15 steps evenly in
# log L/D; eps up to 0.99, denser near 1, where the films part most.  Rows along
# the half length: at least 3 per radius (dzeta <= 1/3; at L/D = 8 the load is
# then within 0.2 % (eps = 0.5) and 0.5 % (0.95) of 6 per radius's), in
# multiples of 12 (few compiles).
MAP_LENGTH_OVER_DIAMETER = [round(0.05 * 400.0 ** (k / 14), 4) for k in range(15)]
MAP_ECCENTRICITY = [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.85, 0.9, 0.93, 0.95,
                    0.97, 0.98, 0.99]
ROWS_PER_RADIUS = 3


def map_rows(length_over_diameter: float) -> int:
    """Grid rows along the half length for the validity map at this L/D."""
    return max(12, 12 * math.ceil(ROWS_PER_RADIUS * length_over_diameter / 12))


# Raimondi & Boyd (g): the plain journal bearing of tests/test_finite_bearing.py
# (R = 10 mm, c = 20 um, mu = 0.02 Pa s, 100 rad/s), the film saturated at 0.995
RB_MU, RB_R, RB_C, RB_OMEGA = 0.02, 0.010, 20e-6, 100.0
RB_LENGTH_OVER_DIAMETER = [0.25, 0.5, 1.0]
RB_ECCENTRICITY = [round(0.05 * k, 2) for k in range(1, 19)] + [0.93, 0.95, 0.97]


def _jax():
    sys.path.insert(0, str(ROOT / "src"))
    import jax

    jax.config.update("jax_enable_x64", True)
    return jax


def _write_csv(path: Path, columns: dict[str, list]) -> None:
    names = list(columns)
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(names)
        for row in zip(*(columns[n] for n in names)):
            w.writerow([f"{float(v):.{SIGNIFICANT}g}" for v in row])


def steady_films() -> None:
    """(a) Each film at steady states (e_dot = 0): load along (radial) and
    across (tangential) the line of centres."""
    _jax()
    import jax.numpy as jnp
    import numpy as np

    from diffwear.contact import PinKinematics, ShortBearingFilm
    from diffwear.contact.long_bearing import LongBearingFilm

    eps = np.round(np.arange(0.05, 0.951, 0.05), 2)
    cols = {"eps": list(eps)}
    for name, film in (("short", ShortBearingFilm(MU, L_SHORT, C)),
                       ("long", LongBearingFilm(MU, L_LONG, C))):
        radial, tangential = [], []
        for e in eps:
            kin = PinKinematics(offset=jnp.array([e * C, 0.0]), offset_rate=jnp.zeros(2),
                                omega=jnp.asarray(OMEGA), pin_radius=jnp.asarray(R),
                                bushing_radius=jnp.asarray(R + C))
            f = film.film(kin)
            radial.append(float(f.radial))
            tangential.append(float(f.tangential))
        cols[f"{name}_radial_N"] = radial
        cols[f"{name}_tangential_N"] = tangential
    _write_csv(STORE / "steady_films.csv", cols)
    meta = {"viscosity_Pa_s": MU, "pin_radius_m": R, "clearance_m": C, "omega_rad_s": OMEGA,
            "short_length_m": L_SHORT, "long_length_m": L_LONG}
    (STORE / "steady_films.json").write_text(json.dumps(meta, indent=1) + "\n")


def _short_eps(load: float) -> float:
    """The short bearing's steady eps for a load [N] (closed form, bisection)."""
    def w(eps):
        return (MU * OMEGA * R * L_SHORT**3 * eps / (4 * C**2 * (1 - eps**2) ** 2)
                * math.sqrt(16 * eps**2 + math.pi**2 * (1 - eps**2)))
    lo, hi = 0.0, 1.0 - 1e-12
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if w(mid) < load else (lo, mid)
    return 0.5 * (lo + hi)


def sommerfeld() -> None:
    """(b) The film-borne journal's quasi-static eccentricity under a steady
    load, and the closed-form eps(S)."""
    _jax()
    import equinox as eqx
    import jax.numpy as jnp
    import numpy as np

    from diffwear.contact import (
        ArchardWear,
        ClearanceJoint,
        CoulombFriction,
        ElasticFoundation,
        MixedLubrication,
        ShortBearingFilm,
    )
    from diffwear.quasistatic import LubricatedQuasiStaticJoint

    law = MixedLubrication(ShortBearingFilm(MU, L_SHORT, C), ElasticFoundation(KF, L_SHORT),
                           1e-9)
    joint = ClearanceJoint("j", "a", [0.0, 0.0], "b", [0.0, 0.0], R, R + C, law,
                           friction=CoulombFriction(0.1), wear=ArchardWear(1e-14), n_theta=180)
    qs = LubricatedQuasiStaticJoint.from_joint(joint)
    solve = eqx.filter_jit(lambda w: qs.pin_offset(w, jnp.asarray(OMEGA), qs.dry.clearance))
    loads = np.logspace(-1.0, 3.7, 25)  # 0.1 N .. 5 kN: eps 0.015 .. 0.98
    angle = 0.4
    eps, attitude, ok = [], [], []
    for w in loads:
        e, good = solve(w * jnp.array([math.cos(angle), math.sin(angle)]))
        eps.append(float(jnp.linalg.norm(e)) / C)
        turn = math.atan2(float(e[1]), float(e[0])) - angle
        attitude.append(math.degrees((turn + math.pi) % (2 * math.pi) - math.pi))
        ok.append(float(good))
    closed = [_short_eps(w) for w in loads]
    # Sommerfeld number S = (R / c)^2 mu N / P, N in rev/s, P = W / (2 R L) the
    # load per projected area (Raimondi & Boyd; Hamrock, Schmid & Jacobson)
    n_rps = OMEGA / (2 * math.pi)
    s = [(R / C) ** 2 * MU * n_rps * 2 * R * L_SHORT / w for w in loads]
    _write_csv(STORE / "sommerfeld.csv", {"load_N": list(loads), "sommerfeld": s,
                                          "eps_quasi_static": eps, "eps_closed_form": closed,
                                          "attitude_deg": attitude, "converged": ok})


def life_viscosity() -> None:
    """(c) The rig's quasi-static life to 50 um against the viscosity, and its
    forward-mode derivative."""
    jax = _jax()
    import equinox as eqx
    import jax.numpy as jnp

    from diffwear.contact import MixedLubrication, default_film
    from diffwear.models import QuasiStatic
    from diffwear.studies import rig_21400
    from diffwear.wear.status import name

    _, mech, y0 = rig_21400._setup()
    el = mech.element("crank_rod")
    c = el.bushing_radius - el.pin_radius
    model = QuasiStatic(steps=RIG_STEPS, samples=RIG_SAMPLES)
    eps_max = float(MixedLubrication.saturation(RIG_ROUGHNESS, c))

    def lubricated(mu):
        film = default_film(mu, el.law.depth, c, el.pin_radius, eps_max)
        law = MixedLubrication(film, el.law, RIG_ROUGHNESS)
        return eqx.tree_at(lambda m: m.element("crank_rod").law, mech, law)

    def life(mu):
        r = model.life(lubricated(mu), ("crank_rod",), y0, period=2.0, limit=RIG_LIMIT)
        return r.life[0], r.result

    t0 = time.perf_counter()
    dry = model.life(mech, ("crank_rod",), y0, period=2.0, limit=RIG_LIMIT)
    fast = eqx.filter_jit(life)
    rows = []
    for mu in VISCOSITIES:
        cycles, status = fast(jnp.asarray(mu))
        rows.append({"viscosity_Pa_s": mu, "life_cycles": float(cycles),
                     "status": name(status)})
        print(f"  mu {mu:.3g} Pa s: life {float(cycles):.6g} ({name(status)})",
              flush=True)
    slope = eqx.filter_jit(lambda m: jax.jvp(lambda x: life(x)[0], (m,), (jnp.ones(()),)))
    tangents = []
    for mu in TANGENTS_AT:
        value, d = slope(jnp.asarray(mu))
        tangents.append({"viscosity_Pa_s": mu, "life_cycles": float(value),
                         "dlife_dmu_cycles_per_Pa_s": float(d)})
        print(f"  d(life)/d(mu) at {mu:.3g} Pa s: {float(d):.6g}", flush=True)
    out = {"settings": {"model": f"QuasiStatic(steps={RIG_STEPS}, samples={RIG_SAMPLES})",
                        "limit_m": RIG_LIMIT, "roughness_m": RIG_ROUGHNESS,
                        "clearance_m": float(c), "length_m": float(el.law.depth),
                        "film": type(lubricated(1e-3).element("crank_rod").law.film).__name__,
                        "period_s": 2.0},
           "dry": {"life_cycles": float(dry.life[0]), "status": name(dry.result)},
           "lives": rows, "tangents": tangents,
           "wall_s": round(time.perf_counter() - t0, 1)}
    (STORE / "life_viscosity.json").write_text(json.dumps(out, indent=1) + "\n")


def _tag(mu: float) -> str:
    """The column prefix of viscosity ``mu`` [Pa s] in slider_crank.csv."""
    return f"mu_{1e3 * mu:g}mPas"


def slider_crank() -> None:
    """(d) The lubricated Table 2-1 slider-crank over one crank revolution."""
    _jax()
    import diffrax
    import equinox as eqx
    import jax.numpy as jnp
    import numpy as np

    from diffwear.contact import MixedLubrication, contact_history, default_film
    from diffwear.dynamics import simulate
    from diffwear.dynamics.rosenbrock import Rodas4
    from diffwear.presets import clearance_slider_crank

    mech, y0 = clearance_slider_crank("efm", clearance=SC_CLEARANCE, n_theta=90)
    el = mech.element("crank_rod")
    c = float(el.bushing_radius - el.pin_radius)
    eps_max = float(MixedLubrication.saturation(SC_ROUGHNESS, c))
    ts = jnp.linspace(0.0, 2.0, 401)

    def run(m):
        tr = simulate(m, y0, 2.0, ts=ts, solver=Rodas4(),
                      stepsize_controller=diffrax.PIDController(rtol=1e-8, atol=1e-8))
        h = contact_history(m, "crank_rod", tr.ys)
        return h.offset, h.normal_load, tr.result

    def lubricated_law(mu):
        film = default_film(mu, el.law.depth, c, el.pin_radius, eps_max)
        return MixedLubrication(film, el.law, SC_ROUGHNESS)

    @eqx.filter_jit
    def lubricated(mu):
        return run(eqx.tree_at(lambda m: m.element("crank_rod").law, mech, lubricated_law(mu)))

    cols: dict[str, list] = {"t_s": list(np.asarray(ts))}
    cases = [(_tag(mu), lambda mu=mu: lubricated(jnp.asarray(mu))) for mu in SC_VISCOSITIES]
    cases.append(("dry", lambda: eqx.filter_jit(run)(mech)))
    for tag, go in cases:
        t0 = time.perf_counter()
        offset, load, result = go()
        if result != diffrax.RESULTS.successful:
            raise RuntimeError(f"slider-crank {tag}: the integration failed ({result})")
        offset = np.asarray(offset)
        cols[f"{tag}_x_over_c"] = list(offset[:, 0] / c)
        cols[f"{tag}_y_over_c"] = list(offset[:, 1] / c)
        if tag != "dry":
            cols[f"{tag}_film_ratio"] = list((c - np.hypot(offset[:, 0], offset[:, 1]))
                                             / SC_ROUGHNESS)
        cols[f"{tag}_asperity_load_N"] = list(np.asarray(load))
        print(f"  {tag}: {time.perf_counter() - t0:.0f} s", flush=True)
    _write_csv(STORE / "slider_crank.csv", cols)
    meta = {"clearance_m": c, "roughness_m": SC_ROUGHNESS, "viscosities_Pa_s": SC_VISCOSITIES,
            "length_m": float(el.law.depth), "pin_radius_m": float(el.pin_radius),
            "solver": "Rodas4, rtol = atol = 1e-8", "duration_s": 2.0,
            "film": type(lubricated_law(1e-3).film).__name__}
    (STORE / "slider_crank.json").write_text(json.dumps(meta, indent=1) + "\n")


def four_bar() -> None:
    """(f) The lubricated four-bar's film over a cycle, orbit and steady."""
    _jax()
    import equinox as eqx
    import jax.numpy as jnp
    import numpy as np

    from diffwear.choices import SHIPPED_MECHANISMS
    from diffwear.config.loader import loads as load_text
    from diffwear.mechanism_file.motion import initial_state
    from diffwear.mechanism_file.wear import drive_period
    from diffwear.models import QuasiStatic
    from diffwear.quasistatic import LubricatedQuasiStaticJoint

    key = 'wear = { coefficient = "5.05e-4 mm^3/(N m)" }'
    text = (SHIPPED_MECHANISMS / "four_bar_wear.toml").read_text()
    dry = load_text(text, file="four_bar_wear.toml")
    found = QuasiStatic(samples=FB_SAMPLES).loads(dry.mechanism, ("coupler_rocker",),
                                                  initial_state(dry), drive_period(dry))
    if not bool(found.ok):
        raise RuntimeError("four-bar: the ideal mechanism's loads failed")
    loads = found.joints[0]

    @eqx.filter_jit
    def film(joint):
        return joint.equilibrium(jnp.zeros(joint.n), loads)

    cols: dict[str, list] = {
        "crank_angle_deg": list(360.0 * np.arange(FB_SAMPLES) / FB_SAMPLES),
        "omega_rad_s": list(np.asarray(loads.omega))}
    for mu in FB_VISCOSITIES:
        oiled = load_text(text.replace(key, key + f'\nlubricant = {{ viscosity = "{mu} Pa s", '
                                       f'roughness = "{FB_ROUGHNESS}" }}'),
                          file="four_bar_wear.toml")
        joint = LubricatedQuasiStaticJoint.from_joint(oiled.mechanism.element("coupler_rocker"))
        for tag, model in (("orbit", joint), ("steady", joint.steady())):
            t0 = time.perf_counter()
            eq = film(model)
            if not bool(eq.ok):
                raise RuntimeError(f"four-bar {mu} Pa s, {tag}: the film solve failed")
            cols[f"{_tag(mu)}_{tag}_h_min_um"] = list(np.asarray(eq.min_film_thickness) * 1e6)
            print(f"  {mu} Pa s, {tag}: {time.perf_counter() - t0:.0f} s", flush=True)
    _write_csv(STORE / "four_bar_squeeze.csv", cols)


def _file_run(name: str, folder: str, joint: str, options: list[str],
              runs: Path | None = None) -> None:
    """``diffwear run <name> <options>`` of a shipped file (or the finished
    run folder ``runs``): its summary and its joint's film, into ``folder``."""
    target = STORE / folder
    target.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        source = runs
        if source is None:
            source = Path(tmp) / folder
            subprocess.run([sys.executable, "-m", "diffwear.cli", "run", name,
                            "--out", str(source), *options, "--quiet"], check=True,
                           env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
        shutil.copyfile(source / f"film_{joint}.csv", target / f"film_{joint}.csv")
        summary = json.loads((source / "summary.json").read_text())
        # the shipped file by its place in the repository, not this machine's path
        summary["file"] = f"src/diffwear/config/mechanisms/{name}.toml"
        (target / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")


def rig(runs: Path | None = None) -> None:
    """(e) ``diffwear run rig_lubricated --cycles 21400``: its summary and film."""
    _file_run("rig_lubricated", "rig", "crank_rod", ["--cycles", "21400"], runs)


def four_bar_run() -> None:
    """(e) ``diffwear run four_bar_lubricated --cycles 1000000 --limit 0.05``
    (the file's header command): its summary and film."""
    _file_run("four_bar_lubricated", "four_bar", "coupler_rocker",
              ["--cycles", "1000000", "--limit", "0.05"])


def validity_map() -> None:
    """(f) The finite film's steady load and attitude over (L/D, eps), per unit
    wedge: F / (6 mu omega R^4 / c^2) (`reynolds_forces` at B = eps)."""
    jax = _jax()

    from diffwear.contact.finite_bearing import N_THETA, reynolds_forces

    solve = jax.jit(reynolds_forces, static_argnames=("n_theta", "n_z"))
    cols: dict[str, list] = {"length_over_diameter": [], "eps": [], "n_z": [],
                             "load": [], "attitude_deg": []}
    for ld in MAP_LENGTH_OVER_DIAMETER:
        t0 = time.perf_counter()
        n_z = map_rows(ld)
        for eps in MAP_ECCENTRICITY:
            f_n, f_t = (float(v) for v in solve(eps, 0.0, eps, ld, n_theta=N_THETA, n_z=n_z))
            cols["length_over_diameter"].append(ld)
            cols["eps"].append(eps)
            cols["n_z"].append(n_z)
            cols["load"].append(math.hypot(f_n, f_t))
            cols["attitude_deg"].append(math.degrees(math.atan2(f_t, -f_n)))
        print(f"  L/D {ld:g} ({n_z} rows): {time.perf_counter() - t0:.0f} s", flush=True)
        _write_csv(STORE / "validity_map.csv", cols)  # as it grows: the larger L/D are slow


def raimondi_boyd() -> None:
    """(g) `FiniteBearingFilm` at steady states: S and the attitude angle."""
    _jax()
    import equinox as eqx
    import jax.numpy as jnp

    from diffwear.contact import FiniteBearingFilm, PinKinematics

    @eqx.filter_jit
    def steady(eps, length):
        kin = PinKinematics(offset=eps * RB_C * jnp.array([1.0, 0.0]), offset_rate=jnp.zeros(2),
                            omega=jnp.asarray(RB_OMEGA), pin_radius=jnp.asarray(RB_R),
                            bushing_radius=jnp.asarray(RB_R + RB_C))
        film = FiniteBearingFilm(RB_MU, length, RB_C, max_eccentricity_ratio=0.995).film(kin)
        return jnp.linalg.norm(film.force), jnp.arctan2(film.tangential, -film.radial)

    cols: dict[str, list] = {"length_over_diameter": [], "eps": [], "sommerfeld": [],
                             "attitude_deg": []}
    for ld in RB_LENGTH_OVER_DIAMETER:
        length = 2.0 * RB_R * ld
        for eps in RB_ECCENTRICITY:
            load, phi = steady(jnp.asarray(eps), jnp.asarray(length))
            # S = (R / c)^2 mu N / P, N = omega / 2 pi, P = W / (2 R L)
            s = (RB_R / RB_C) ** 2 * RB_MU * RB_OMEGA / (2 * math.pi) * 2 * RB_R * length
            cols["length_over_diameter"].append(ld)
            cols["eps"].append(eps)
            cols["sommerfeld"].append(s / float(load))
            cols["attitude_deg"].append(math.degrees(float(phi)))
    _write_csv(STORE / "raimondi_boyd.csv", cols)


PARTS = {"steady": steady_films, "sommerfeld": sommerfeld, "life": life_viscosity,
         "slider-crank": slider_crank, "four-bar": four_bar, "rig": rig,
         "four-bar-run": four_bar_run,
         "validity": validity_map, "raimondi-boyd": raimondi_boyd}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", choices=list(PARTS), help="these parts only")
    parser.add_argument("--rig-run", type=Path,
                        help="copy this finished `diffwear run rig_lubricated` folder "
                             "instead of running it")
    args = parser.parse_args(argv)
    STORE.mkdir(parents=True, exist_ok=True)
    for name in args.only or PARTS:
        t0 = time.perf_counter()
        if name == "rig":
            rig(args.rig_run)
        else:
            PARTS[name]()
        print(f"{name}: {time.perf_counter() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
