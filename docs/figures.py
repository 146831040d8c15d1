"""The documentation's figures, drawn at build time from stored data.

Every figure reads the repository's stored runs and records only (no
simulation while the site builds):

* ``design_studies/results/studies/<run>/``: the thesis studies' curves
  (written by ``design_studies/docs_figure_data.py``);
* ``design_studies/results/design_two_joint/``, ``rig_sensitivity.json``: the
  Ch. 8 design run and the rig's sensitivity study;
* ``design_studies/results/studies/sweep-rig-clearance-k/``: the shipped
  sweep file's results;
* ``benchmarks/records/agreement.json``: the quasi-static model against the
  dynamic one;
* ``design_studies/results/studies/lubrication/``: the lubricated joint's
  checks and the lubricated rig's run (written by
  ``design_studies/lubrication_figure_data.py``);
* ``design_studies/calibration/results/<campaign>/``: the stored calibrations'
  residuals (``residuals.csv``), redrawn in degrees.

The thesis's reported values come from the study modules, which cite them
(e.g. `diffwear.studies.rig_21400.THESIS`: Tables 7-4..7-6).  The guides'
figures are drawn by the package's own plot functions (`diffwear.plots`), so a
change to them shows here.  `FIGURES` maps the site path of each figure to the
function that draws it; `draw_all` writes them into a folder.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "design_studies" / "results"
STUDIES = RESULTS / "studies"
RECORDS = ROOT / "benchmarks" / "records"
DPI = 110  # ~770 px for a 7-inch figure: the content column's width

if str(ROOT / "src") not in sys.path:
    sys.path.insert(0, str(ROOT / "src"))


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def read_csv(path: Path) -> dict[str, np.ndarray]:
    """A stored CSV as columns by header name."""
    data = np.genfromtxt(path, delimiter=",", names=True)
    return {name: np.atleast_1d(data[name]) for name in data.dtype.names}


def _summary(run: str) -> dict:
    return json.loads((STUDIES / run / "summary.json").read_text())


class _Folder:
    """The ``out`` a `diffwear.plots.wear.wear_figures` call writes into."""

    def __init__(self, path: Path):
        self.path = path

    def file(self, name: str) -> Path:
        return self.path / name


def _wear_study_figures(run: str, folder: Path) -> None:
    """The wear study's own figures (`diffwear.plots.wear.wear_figures`) from
    its stored curves: profile, history, first/last cycle's locus and force,
    with what the study draws beside them (its joint's clearance and wall, the
    thesis figures it compares with, what it is calibrated to)."""
    from diffwear.plots.wear import Lines, wear_figures
    from diffwear.studies import rig_21400, wear_5000

    module = {"rig-21400": rig_21400, "wear-5000": wear_5000}[run]
    design = module.DESIGN
    s = _summary(run)
    profile = read_csv(STUDIES / run / "wear_profile.csv")
    history = read_csv(STUDIES / run / "wear_history.csv")
    later = history["cycles"] > 0  # the stored history starts at the unworn 0

    def cycle(tag):
        force = read_csv(STUDIES / run / f"joint_force_{tag}_cycle.csv")
        locus = read_csv(STUDIES / run / f"contact_locus_{tag}_cycle.csv")
        offset = np.stack([locus["offset_x_mm"], locus["offset_y_mm"]], axis=1) * 1e-3
        return force["crank_angle_rad"], SimpleNamespace(offset=offset,
                                                         force_magnitude=force["force_N"])

    crank, first = cycle("first")
    _, last = cycle("last")
    wear_figures(_Folder(folder), name=run, theta=profile["theta_rad"],
                 depth_mm=profile["depth_mm"],
                 history=(history["cycles"][later], history["max_depth_mm"][later],
                          history["volume_mm3"][later]),
                 crank=crank, first=first, last=last, thesis=s["thesis"],
                 lines=Lines(clearance_mm=1e3 * float(design.clearance),
                             wall_mm=1e3 * float(design.wall),
                             cf=getattr(module, "CF", ""),
                             calibrated=getattr(module, "CALIBRATED", "")))


_WEAR_STUDY_PNGS: dict[str, dict[str, bytes]] = {}  # run -> its figures, drawn once


def wear_study(run: str, figure: str) -> Callable[[Path], None]:
    """Figure ``figure`` (wear_profile.png, wear_history.png,
    contact_locus_and_force.png) of the stored wear study ``run``."""
    def draw(path: Path) -> None:
        import tempfile

        if run not in _WEAR_STUDY_PNGS:
            with tempfile.TemporaryDirectory() as tmp:
                _wear_study_figures(run, Path(tmp))
                _WEAR_STUDY_PNGS[run] = {p.name: p.read_bytes() for p in Path(tmp).glob("*.png")}
        path.write_bytes(_WEAR_STUDY_PNGS[run][figure])
    return draw


def rig_profile_against_thesis(path: Path) -> None:
    """Ch. 7: the rig's worn profile (dynamic model, EFM and FEM routes) and,
    beside it, the maximum depths of both routes, the thesis's models and the
    measured bushing, one column each (the thesis gives maxima, no profiles).
    The worn volume is not compared: the spring's free length is fitted to
    the thesis models' volume, so it agrees by construction (said in the
    caption line)."""
    from diffwear.plots.references import maxima_strip
    from diffwear.studies.rig_21400 import TARGET_VOLUME_MM3

    plt = _pyplot()
    efm = read_csv(STUDIES / "rig-21400" / "wear_profile.csv")
    s = _summary("rig-21400")
    fem_run = STUDIES / "rig-21400-fem"
    fig, (a, b) = plt.subplots(1, 2, figsize=(10.5, 4.2), sharey=True,
                               gridspec_kw={"width_ratios": [2.2, 1.25]})
    a.plot(np.degrees(efm["theta_rad"]), efm["depth_mm"], lw=1.8, label="diffwear, EFM route")
    maxima = [("diffwear (EFM route)", s["max_wear_depth_mm"])]
    if (fem_run / "wear_profile.csv").is_file():
        fem = read_csv(fem_run / "wear_profile.csv")
        fem_s = _summary("rig-21400-fem")
        arc = fem_s["fem_route"]["arc_peak_depth_mm"]
        a.plot(np.degrees(fem["theta_rad"]), fem["depth_mm"], lw=1.2, ls="--",
               color="tab:orange", label="diffwear, FEM route: node-to-node roughness of "
                                         "about one wear step (FEM page)")
        maxima.append(("diffwear (FEM route, ±4° mean)", arc))
    maxima += [(f"thesis {k}", v["max_wear_depth_mm"]) for k, v in s["thesis"].items()]
    maxima_strip(b, maxima)
    b.tick_params(axis="x", labelsize=6.5)
    a.set(xlabel="bushing angle θ [deg]", ylabel="wear depth [mm]", xlim=(0, 360),
          xticks=np.arange(0, 361, 45), ylim=(-0.02, 0.6),
          title="Rig bushing after 21,400 cycles: worn profile")
    a.legend(fontsize=7, loc="upper left")
    a.grid(alpha=0.3)
    measured = s["thesis"]["measured (Tables 7-5/7-6)"]["wear_volume_mm3"]
    fig.text(0.01, 0.01, f"Worn volume not compared: the slider spring's free length is "
                         f"fitted so that diffwear's equals the thesis models' "
                         f"{TARGET_VOLUME_MM3:g} mm³ (Table 7-4); the measured bushing lost "
                         f"{measured:g} mm³ (Tables 7-5/7-6).", fontsize=7.5, va="bottom")
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def rig_joint_force(path: Path) -> None:
    """The rig's crank-rod joint force over its first and last cycles, and
    beside it the thesis's Fig. 7-2 range (0-200 N) with its mean of about
    130 N, as a bar on its own axis (the thesis's curve is not tabulated)."""
    plt = _pyplot()
    fig, (ax, ref) = plt.subplots(1, 2, figsize=(7.6, 3.6), sharey=True,
                                  gridspec_kw={"width_ratios": [6, 1]})
    curves = {tag: read_csv(STUDIES / "rig-21400" / f"joint_force_{tag}_cycle.csv")
              for tag in ("first", "last")}
    gap = float(np.max(np.abs(curves["last"]["force_N"] - curves["first"]["force_N"])))
    for tag, f in curves.items():
        ax.plot(np.degrees(f["crank_angle_rad"]), f["force_N"],
                lw=2.0 if tag == "first" else 1.2, ls="-" if tag == "first" else "--",
                label=f"diffwear, {tag} cycle (mean {np.mean(f['force_N']):.0f} N)")
    ax.set(xlabel="crank angle [deg]", ylabel="joint force [N]", xlim=(0, 360),
           xticks=np.arange(0, 361, 45), ylim=(0, 220),
           title=f"Rig crank-rod joint force (the cycles differ by at most {gap:.2g} N)")
    ax.title.set_fontsize(9)
    ax.legend(fontsize=7, loc="lower center")
    ax.grid(alpha=0.3)
    # thesis Fig. 7-2: the measured joint force spans 0-200 N about a mean of ~130 N
    ref.errorbar([0.0], [130.0], yerr=[[130.0], [70.0]], fmt="D", mfc="none", color="k",
                 capsize=6, ms=6)
    ref.set(xlim=(-1, 1), xticks=[0], title="thesis\nFig. 7-2")
    ref.set_xticklabels(["range 0-200 N,\nmean ~130 N"], fontsize=7)
    ref.title.set_fontsize(8)
    ref.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def wear_5000_against_thesis(path: Path) -> None:
    """Ch. 5-6: the wear example's profile with the Table 6-4 maxima, and the
    depth and volume beside the thesis's EFM and FEM."""
    wear_study("wear-5000", "wear_profile.png")(path)


def ideal_reaction(path: Path) -> None:
    """Ch. 2: the ideal slider-crank's crank-rod reaction (cf. Fig. 2-10) and
    the constraint drift against the Baumgarte gains (cf. Fig. 2-8)."""
    from diffwear import plots

    r = read_csv(STUDIES / "ideal-slider-crank" / "reaction_crank_rod.csv")
    v = read_csv(STUDIES / "ideal-slider-crank" / "constraint_violation.csv")
    gains = {k.replace("_m", "").replace("alpha", "α = β = ").split("_beta")[0]: np.abs(v[k])
             for k in v if k.startswith("alpha")}
    plots.stacked(path, r["t_s"], [
        ("force on rod [N]", {"Fx": r["fx_N"], "Fy": r["fy_N"],
                              "|F|": np.hypot(r["fx_N"], r["fy_N"])}),
        ("|Φ₂| [m]", {f"{k} 1/s": g for k, g in gains.items()}),
    ], xlabel="time [s] (one crank revolution)", logy=[False, True],
        title="Table 2-1 slider-crank: crank-rod reaction (cf. Fig. 2-10) and constraint "
              "drift by Baumgarte gains (cf. Fig. 2-8)")


def clearance_forces(path: Path) -> None:
    """Ch. 3/6: the joint force of each contact law at each Table 3-2
    clearance against the ideal joint's, over the last cycle (cf. Figs.
    3-7/6-8)."""
    from diffwear import plots

    folder = STUDIES / "clearance-sweep"
    ideal = read_csv(folder / "force_ideal.csv")
    panels = []
    for law in ("ln", "kv", "efm"):
        curves = {}
        # largest clearance first (drawn under the others), as the study's figures
        files = sorted(folder.glob(f"force_{law}_*.csv"),
                       key=lambda p: -float(p.stem.split("_")[-1]))
        x = None
        for file in files:
            c = read_csv(file)
            angle = np.degrees(c["crank_angle_rad"]) % 360.0
            order = np.argsort(angle)
            x = angle[order]
            curves[f"c = {file.stem.split('_')[-1]} mm"] = c["force_N"][order]
        if x is None:
            raise FileNotFoundError(f"{folder}: no force_{law}_*.csv")
        curves["ideal joint"] = np.interp(x, np.degrees(ideal["crank_angle_rad"]) % 360.0,
                                          ideal["force_N"], period=360.0)
        panels.append((f"{law.upper()} |F| [N]", curves))
    plots.stacked(path, x, panels, xlabel="crank angle [deg] (last cycle)",
                  title="Crank-rod joint force by contact law and radial clearance, "
                        "against the ideal joint (cf. Figs. 3-7/6-8)")


def clearance_loci(path: Path) -> None:
    """Ch. 3/5/6: the pin centre in the bushing while in contact, at the
    largest Table 3-2 clearance, per law (cf. Figs. 5-4/6-7)."""
    from diffwear import plots

    loci = {}
    for law in ("ln", "kv", "efm"):
        for file in sorted((STUDIES / "clearance-sweep").glob(f"locus_{law}_*.csv")):
            c_mm = float(file.stem.split("_")[-1])
            c = read_csv(file)
            touching = c["in_contact"] > 0
            radius = np.hypot(c["offset_x_m"], c["offset_y_m"]) / (1e-3 * c_mm)
            loci[f"{law.upper()}, c = {c_mm:g} mm"] = (c["theta_rad"][touching],
                                                      radius[touching])
    plots.polar_loci(path, loci, title="Contact locus on the bushing, last cycle (rod frame; "
                                       "cf. Figs. 5-4, 6-7)",
                     radius_label="|e| / clearance", radius_scale=1.0)


def pin_pivot_history(path: Path) -> None:
    """Ch. 4: max wear of pin and pivot against sweeps, the linear
    extrapolation to 408,000 test cycles and the thesis's values (cf. Fig. 4-9)."""
    from diffwear.plots.pin_pivot import history_figure
    from diffwear.studies.pin_pivot import TARGET_SWEEPS, THESIS
    from diffwear.studies.pin_pivot_integrator import steady_line

    h = read_csv(STUDIES / "pin-pivot" / "history.csv")
    history_figure(path, sweeps=h["sweeps"], max_pin_mm=h["max_pin_mm"],
                   max_pivot_mm=h["max_pivot_mm"],
                   fit_pin=steady_line(h["sweeps"], h["max_pin_mm"] * 1e-3),
                   fit_pivot=steady_line(h["sweeps"], h["max_pivot_mm"] * 1e-3),
                   target=TARGET_SWEEPS, direct=None, thesis=THESIS,
                   title="pin-pivot: max wear vs sweeps (cf. thesis Fig. 4-9)")


def pin_pivot_profiles(path: Path) -> None:
    """Ch. 4: pin and pivot wear profiles and the contact pressure at mid-stroke."""
    from diffwear.plots.pin_pivot import profile_figure

    p = read_csv(STUDIES / "pin-pivot" / "profiles.csv")
    s = _summary("pin-pivot")
    sweeps = int(s["simulated_sweeps"])
    profile_figure(path, angle_deg=p["angle_deg"],
                   simulated={f"pin, {sweeps:,} sweeps": p["pin_depth_mm_simulated"],
                              f"pivot, {sweeps:,} sweeps": p["pivot_depth_mm_simulated"]},
                   direct={f"pin, {2 * sweeps:,} sweeps (direct)": p["pin_depth_mm_direct"],
                           f"pivot, {2 * sweeps:,} sweeps (direct)":
                               p["pivot_depth_mm_direct"]},
                   pressure=p["pressure_MPa_mid_stroke_end"],
                   title=f"pin-pivot: wear profiles (R {1e3 * s['setup']['pin_radius']:g} mm, "
                         "load fixed to the pivot)")


def life_map(joint: int) -> Callable[[Path], None]:
    """Ch. 8: joint ``joint``'s life over its (diameter, depth) box, with the
    stored equal-life answer and the thesis's Table 8-4 design."""
    def draw(path: Path) -> None:
        from diffwear.design.two_joint import TABLE_8_4
        from diffwear.plots.design import life_map as draw_map

        folder = RESULTS / "design_two_joint"
        rows = read_csv(folder / "life_maps.csv")
        s = json.loads((folder / "summary.json").read_text())
        maps: dict[str, np.ndarray] = {}
        for j in (1, 2):
            mine = rows["joint"] == j
            d, h = np.unique(rows["d_mm"][mine]), np.unique(rows["h_mm"][mine])
            grid = np.full((d.size, h.size), np.nan)
            grid[np.searchsorted(d, rows["d_mm"][mine]),
                 np.searchsorted(h, rows["h_mm"][mine])] = rows["cycles"][mine]
            maps.update(d_m=d * 1e-3, h_m=h * 1e-3)
            maps[f"cyc{j}"] = grid
        answer = 1e-3 * np.array([s["d1_mm"], s["d2_mm"], s["h1_mm"], s["h2_mm"]])
        draw_map(path, maps, joint, answer, np.asarray(TABLE_8_4))
    return draw


def rig_tornado(output: str) -> Callable[[Path], None]:
    """The rig's elasticities of ``output`` by reverse-mode AD (stored study
    ``rig_sensitivity.json``), as `diffwear.plots.sweep.tornado` draws them."""
    def draw(path: Path) -> None:
        from diffwear.plots.sweep import quantity, tornado
        from diffwear.sweep.sensitivity import Sensitivity

        s = json.loads((RESULTS / "rig_sensitivity.json").read_text())
        y = s["outputs"]
        # dy/dp back from the stored elasticity e = (p / y) dy/dp
        gradient = {o: {p: e * y[o] / s["point"][p] for p, e in es.items()}
                    for o, es in s["elasticity_ad"].items()}
        settings = s["settings"]
        tornado(path, Sensitivity(s["point"], y, gradient), output,
                title=f"rig, {settings['cycles']:,.0f} cycles: sensitivity of the "
                      f"{quantity(output).split(' [')[0]} (reverse-mode AD)")
    return draw


def rig_sweep_heatmap(output: str) -> Callable[[Path], None]:
    """``<output>.png`` of ``diffwear sweep design_studies/sweep_rig_clearance_k.toml``
    (stored run on the quasi-static joint model), as the command draws it:
    `diffwear.plots.sweep.heatmap` with the sweep file's axes and units."""
    def draw(path: Path) -> None:
        from diffwear.cli.sweep import label, shown
        from diffwear.config.sweep import load_sweep
        from diffwear.plots.sweep import heatmap, quantity

        spec = load_sweep(ROOT / "design_studies" / "sweep_rig_clearance_k.toml")
        rows = read_csv(STUDIES / "sweep-rig-clearance-k" / "results.csv")
        gy, gx = spec.grid  # the file's first axis down, its second across (grid order)
        columns = {name: next(c for c in rows if c == name or c.startswith(f"{name}_"))
                   for name in (gy, gx)}
        y, x = (np.unique(rows[columns[name]]) for name in (gy, gx))
        z = rows[output].reshape(y.size, x.size)
        heatmap(path, shown(spec, gx, x), shown(spec, gy, y), z,
                xlabel=label(spec, gx), ylabel=label(spec, gy), zlabel=quantity(output),
                title=f"rig, 21,400 cycles, quasi-static joint model: "
                      f"{quantity(output).split(' [')[0]}")
    return draw


def agreement(path: Path) -> None:
    """The quasi-static model against the dynamic one: relative differences of
    the wear studies' depth and volume and of the Ch. 8 lives."""
    plt = _pyplot()
    data = json.loads((RECORDS / "agreement.json").read_text())
    labels, values = [], []
    for study, r in data["wear_studies"].items():
        labels += [f"{study}\nmax depth", f"{study}\nvolume"]
        values += [r["depth_rel_diff"], r["volume_rel_diff"]]
    for design, r in data["ch8"]["designs"].items():
        for j, v in enumerate(r["rel_diff_to_extrapolated"], 1):
            labels.append(f"Ch. 8 {design}\nlife, joint {j}")
            values.append(v)
    fig, ax = plt.subplots(figsize=(7, 0.42 * len(labels) + 1.3))
    y = np.arange(len(labels))
    ax.barh(y, 100 * np.asarray(values), color=["tab:blue" if abs(v) < 0.01 else "tab:red"
                                                 for v in values])
    ax.axvline(1.0, color="k", ls="--", lw=0.9, label="goal: within 1 %")
    ax.axvline(-1.0, color="k", ls="--", lw=0.9)
    ax.axvline(0.0, color="k", lw=0.6)
    ax.set_yticks(y, labels, fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("quasi-static minus dynamic, relative [%]")
    ax.set_title("Quasi-static against dynamic model (benchmarks/records/agreement.json)",
                 fontsize=10)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, axis="x")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def _record(name: str) -> dict:
    return json.loads((RECORDS / f"{name}.json").read_text())


def performance_costs(path: Path) -> None:
    """The performance page's figure, from the benchmark records: left, the
    run time of the rig's wear over N crank cycles by route (each recorded
    run a marker; the every-cycle route's time proportional to N, dotted
    beyond its run); right, the time of a sweep against its number of
    designs, on the 2-core CPU (a process per core; linear in the count,
    dotted beyond the recorded run) and in the GPU first look (its recorded
    runs only: a batch's throughput grows with its size)."""
    from diffwear.plots.references import side_by_side
    from diffwear.studies.rig_21400 import THESIS

    plt = _pyplot()
    fig, (a, b) = plt.subplots(1, 2, figsize=(11.5, 6.2))

    # ---- left: the rig's wear over N cycles
    every = json.loads((RESULTS / "wear_convergence_2000.json").read_text())
    n_every = every["cycles"]
    t_every = every["runs"]["every cycle (A = 1)"]["wall_time_s_incl_compile"]
    n = np.geomspace(1e2, 1e6, 50)
    a.plot([n_every], [t_every], "o", color="tab:red", ms=6,
           label=f"dynamic, every cycle simulated (Tsit5; {n_every:,} cycles, incl. compile)")
    a.plot(n, t_every * n / n_every, ":", color="tab:red", lw=1.2,
           label="  the same, proportional to N")
    full = _record("full_2d4674c_quiet")["cases"]["rig-21400 (constant A)"]
    rodas = _record("study_and_exudyn_static_ground")["runs"]["rig-21400 (Rodas4)"]["case"]
    quasi = _record("quasi_static")["cases"]["rig-21400 quasi-static"]
    n_rig = 21400.0
    for t, marker, color, label in (
            (full["run_s"], "s", "tab:green", "dynamic, 51 simulated cycles (Tsit5)"),
            (rodas["run_s"], "D", "tab:purple", "dynamic, 51 simulated cycles (Rodas4)"),
            (quasi["run_s"], "^", "tab:blue", "quasi-static (wear ODE in N)")):
        a.plot([n_rig], [t], marker, color=color, ms=7, label=f"{label}: {t:.3g} s")
    side_by_side(a, n_rig, [(f"thesis {ref}: {THESIS[ref]['time_h']:g} h",
                             3600.0 * THESIS[ref]["time_h"])
                            for ref in ("EFM (Table 7-4)", "FEM (Table 7-4)")], first_pt=-4.5)
    a.set(xscale="log", yscale="log", xlabel="crank cycles of wear N",
          ylabel="run time [s] (after compiling)", xlim=(1e2, 1e6), ylim=(0.05, 2e5),
          title="Ch. 7 rig: wear over N cycles (2-core CPU)")
    a.grid(alpha=0.3, which="both")
    a.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14))

    # ---- right: a sweep over designs
    lives = _record("quasi_static")["cases"]["quasi-static life sweep, 1000 designs"]
    sweep = _record("cpu_sweep")["cases"]
    rig_qs = next(v for k, v in sweep.items() if "quasi-static rig" in k)
    rig_dyn = next(v for k, v in sweep.items() if "dynamic rig" in k)
    gpu = _record("gpu_first_look")["cases"]
    designs = np.geomspace(1, 1e5, 50)
    cpu = (("Ch. 8 lives (quasi-static)", lives["designs"], lives["run_s"], "tab:blue"),
           ("rig, 21,400 cycles (quasi-static)", rig_qs["points"], rig_qs["auto_s"],
            "tab:orange"),
           ("rig, 21,400 cycles (dynamic, 50 dynamic cycles)", rig_dyn["points"], rig_dyn["auto_s"],
            "tab:green"))
    for label, count, t, color in cpu:
        b.plot([count], [t], "o", color=color, ms=6, label=f"CPU: {label}")
        b.plot(designs, t * designs / count, ":", color=color, lw=1.1)
    first = (("quasi-static two-joint lives (Ch. 8 box)", "gpu_designs", "tab:blue"),
             ("quasi-static rig, 21,400 cycles", "gpu_points", "tab:orange"),
             ("dynamic rig, 21,400 cycles at 3 dynamic cycles", "gpu_points", "tab:green"))
    for case, key, color in first:
        g = gpu[case]
        b.plot([g[key]], [g["gpu_s"]], "D", mfc="none", mew=1.4, color=color, ms=7,
               label=f"GPU first look: {case} ({g[key]:,})")
    b.set(xscale="log", yscale="log", xlabel="designs (sweep points)",
          ylabel="run time [s] (after compiling)", xlim=(1, 1e5), ylim=(0.1, 1e5),
          title="A sweep against its number of designs")
    b.grid(alpha=0.3, which="both")
    b.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14))
    fig.text(0.01, 0.01, "Dotted: a recorded run scaled linearly (cost proportional to cycles "
                         "or designs).  Records: benchmarks/records/ (full_2d4674c_quiet, "
                         "study_and_exudyn_static_ground, quasi_static, cpu_sweep,\n"
                         "gpu_first_look) and design_studies/results/wear_convergence_2000.json.",
             fontsize=7, va="bottom")
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def results_against_thesis(path: Path) -> None:
    """The wear studies' depth and volume, diffwear over each of the thesis's
    values (its EFM and FEM models, the measurement)."""
    plt = _pyplot()
    rows = []  # (label, diffwear, {reference: value})
    for run in ("rig-21400", "wear-5000"):
        s = _summary(run)
        for key, unit in (("max_wear_depth_mm", "max depth"), ("wear_volume_mm3", "volume")):
            refs = {k: v[key] for k, v in s["thesis"].items() if key in v}
            if run == "rig-21400" and key == "wear_volume_mm3":
                # fitted to the thesis models' volume (the spring's free length):
                # only the measurement is a comparison
                refs = {k: v for k, v in refs.items() if k.startswith("measured")}
                unit = "volume\n(models': fitted)"
            rows.append((f"{run}\n{unit}", s[key], refs))
    from diffwear.plots.references import STYLES

    # each reference on its own line within a row: near-equal ratios never hide
    shift = {"EFM": -0.2, "FEM": 0.0, "measured": 0.2}
    fig, ax = plt.subplots(figsize=(7.5, 3.8))
    for i, (_, ours, refs) in enumerate(rows):
        for ref, value in refs.items():
            kind = next(k for k in STYLES if ref.startswith(k))
            marker, color = STYLES[kind]
            ax.plot(ours / value, i + shift[kind], marker, ms=7, mfc="none", mew=1.5,
                    color=color,
                    label="against the measurement" if kind == "measured"
                    else f"against thesis {kind}")
    handles, names = ax.get_legend_handles_labels()
    unique = dict(zip(names, handles))
    ax.legend(unique.values(), list(unique), fontsize=8,
              loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.axvline(1.0, color="k", lw=0.8)
    ax.set_yticks(range(len(rows)), [r[0] for r in rows], fontsize=8)
    ax.set_ylim(len(rows) - 0.5, -0.5)
    ax.set_xlabel("diffwear / thesis")
    ax.set_title("Wear studies: diffwear over the thesis's models and measurement "
                 "(Tables 6-4, 7-4..7-6)", fontsize=9)
    ax.grid(alpha=0.3, axis="x")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


LUBRICATION = STUDIES / "lubrication"


def _short_steady(eps):
    """The short bearing's steady load over mu omega R L^3 / c^2 and its
    attitude [deg] (Hamrock, Schmid & Jacobson, the short-width journal
    bearing)."""
    w = eps / (4.0 * (1.0 - eps**2) ** 2) * np.sqrt(16.0 * eps**2 + np.pi**2 * (1.0 - eps**2))
    return w, np.degrees(np.arctan2(np.pi * np.sqrt(1.0 - eps**2), 4.0 * eps))


def _long_steady(eps):
    """The long (half-Sommerfeld) bearing's steady load over
    mu omega R^3 L / c^2 and its attitude [deg] (same source)."""
    w_r = 12.0 * eps**2 / ((2.0 + eps**2) * (1.0 - eps**2))
    w_t = 6.0 * np.pi * eps / ((2.0 + eps**2) * np.sqrt(1.0 - eps**2))
    return np.hypot(w_r, w_t), np.degrees(np.arctan2(w_t, w_r))


def lubrication_short_bearing(path: Path) -> None:
    """The short- and long-bearing films at steady states (the laws'
    ``film``, stored) against their closed-form load and attitude."""
    plt = _pyplot()
    d = read_csv(LUBRICATION / "steady_films.csv")
    m = json.loads((LUBRICATION / "steady_films.json").read_text())
    mu, omega, r, c = m["viscosity_Pa_s"], m["omega_rad_s"], m["pin_radius_m"], m["clearance_m"]
    scales = {"short": mu * omega * r * m["short_length_m"] ** 3 / c**2,
              "long": mu * omega * r**3 * m["long_length_m"] / c**2}
    closed = {"short": _short_steady, "long": _long_steady}
    words = {"short": f"short bearing (L/D = {m['short_length_m'] / (2 * r):g}), "
                      "W / (ηωRL³/c²)",
             "long": f"long bearing (L/D = {m['long_length_m'] / (2 * r):g}), W / (ηωR³L/c²)"}
    eps = d["eps"]
    line = np.linspace(0.01, 0.96, 300)
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.9))
    for (name, color) in (("short", "tab:blue"), ("long", "tab:orange")):
        load, attitude = closed[name](line)
        a.plot(line, load, color=color, lw=1.3, label=f"{words[name]}: closed form")
        b.plot(line, attitude, color=color, lw=1.3, label=f"{name} bearing: closed form")
        radial, tangential = d[f"{name}_radial_N"], d[f"{name}_tangential_N"]
        a.plot(eps, np.hypot(radial, tangential) / scales[name], "o", ms=4.5, mfc="none",
               color=color, label=f"{name} bearing: diffwear's film law")
        b.plot(eps, np.degrees(np.arctan2(tangential, -radial)), "o", ms=4.5, mfc="none",
               color=color, label=f"{name} bearing: diffwear's film law")
    a.set(yscale="log", xlabel="eccentricity ratio ε", ylabel="dimensionless load",
          xlim=(0, 1), title="Steady load")
    b.set(xlabel="eccentricity ratio ε", ylabel="attitude angle φ [deg]", xlim=(0, 1),
          ylim=(0, 95), title="Attitude (load line to line of centres)")
    a.legend(fontsize=7, loc="upper left")
    b.legend(fontsize=7, loc="upper right")
    for ax in (a, b):
        ax.grid(alpha=0.3, which="both")
    fig.suptitle("Steady films against Hamrock, Schmid & Jacobson's closed forms "
                 f"(R {1e3 * r:g} mm, c {1e6 * c:g} µm, η {mu:g} Pa s, ω {omega:g} rad/s)",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def lubrication_sommerfeld(path: Path) -> None:
    """The quasi-static equilibrium of a film-borne journal (stored) against
    the short bearing's closed-form eccentricity and attitude against the
    Sommerfeld number."""
    plt = _pyplot()
    d = read_csv(LUBRICATION / "sommerfeld.csv")
    m = json.loads((LUBRICATION / "steady_films.json").read_text())
    mu, omega, r, c, length = (m["viscosity_Pa_s"], m["omega_rad_s"], m["pin_radius_m"],
                               m["clearance_m"], m["short_length_m"])
    eps = np.linspace(0.005, 0.985, 400)
    load, attitude = _short_steady(eps)
    load = load * mu * omega * r * length**3 / c**2
    s = (r / c) ** 2 * mu * omega / (2 * np.pi) * 2 * r * length / load
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.8))
    a.plot(s, eps, lw=1.3, label="short bearing, closed form ε(S)")
    a.plot(d["sommerfeld"], d["eps_quasi_static"], "o", ms=4.5, mfc="none",
           label="diffwear: quasi-static equilibrium")
    b.plot(s, attitude, lw=1.3, label="short bearing, closed form φ(S)")
    b.plot(d["sommerfeld"], d["attitude_deg"], "o", ms=4.5, mfc="none",
           label="diffwear: quasi-static equilibrium")
    a.set(xscale="log", xlabel="Sommerfeld number S = (R/c)² ηN / P", ylim=(0, 1),
          ylabel="eccentricity ratio ε", title="Eccentricity of the equilibrium")
    b.set(xscale="log", xlabel="Sommerfeld number S = (R/c)² ηN / P", ylim=(0, 95),
          ylabel="attitude angle φ [deg]", title="Attitude of the equilibrium")
    a.legend(fontsize=7, loc="upper right")
    b.legend(fontsize=7, loc="lower right")
    for ax in (a, b):
        ax.grid(alpha=0.3, which="both")
    fig.suptitle(f"Film-borne journal under a steady load {d['load_N'].min():.1g} .. "
                 f"{d['load_N'].max():.0f} N (σ = 1 nm: no asperity contact; N in rev/s, "
                 "P = W / 2RL)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


# The stored runs' film laws (their class names) in a figure's words.
FILM_WORDS = {"ShippedFiniteFilm": "finite-length film", "FiniteBearingFilm": "finite-length film",
              "ShortBearingFilm": "short-bearing film", "LongBearingFilm": "long-bearing film"}


def lubrication_life_viscosity(path: Path) -> None:
    """The Ch. 7 rig's quasi-static life to 50 µm against the viscosity
    (stored), the dry life and the forward-mode slopes d(life)/d(mu)."""
    plt = _pyplot()
    s = json.loads((LUBRICATION / "life_viscosity.json").read_text())
    mu = np.array([r["viscosity_Pa_s"] for r in s["lives"]])
    life = np.array([r["life_cycles"] for r in s["lives"]])
    done = np.isfinite(life)
    # a life far beyond the others (a joint that nearly runs in) is written
    # at the top, not drawn: it would flatten the rest of the curve
    off = done & (life > 20.0 * s["dry"]["life_cycles"])
    fig, ax = plt.subplots(figsize=(7.5, 4.0))
    shown = done & ~off
    ax.plot(mu[shown], life[shown], "o-", ms=4, lw=1.2, label="lubricated, quasi-static life")
    ax.axhline(s["dry"]["life_cycles"], color="k", ls="--", lw=1.0,
               label=f"dry joint: {s['dry']['life_cycles']:,.0f} cycles")
    for k, t in enumerate(s["tangents"]):
        x0, y0, slope = t["viscosity_Pa_s"], t["life_cycles"], t["dlife_dmu_cycles_per_Pa_s"]
        x = x0 * np.array([0.7, 1.0 / 0.7])
        ax.plot(x, y0 + slope * (x - x0), color="tab:red", lw=2.2, alpha=0.8,
                label="d(life)/dη by jax.jvp (tangent)" if k == 0 else None)
    top = float(np.nanmax(life[shown])) if shown.any() else s["dry"]["life_cycles"]
    for x, y in zip(mu[off], life[off]):
        ax.annotate(f"{y:,.0f}\ncycles", xy=(x, 1.1 * top), ha="center", va="center",
                    fontsize=7, color="tab:blue")
    for x in mu[~done]:
        ax.annotate("", xy=(x, 1.12 * top), xytext=(x, 0.97 * top),
                    arrowprops={"arrowstyle": "->", "color": "tab:green", "lw": 1.5})
    if (~done).any():
        ax.plot([], [], color="tab:green", marker=r"$\uparrow$", ls="none", ms=9,
                label=f"runs in: 50 µm never reached (η ≥ {mu[~done].min():g} Pa s)")
    st = s["settings"]
    ax.set(xscale="log", xlabel="viscosity η [Pa s]", ylabel="cycles to 50 µm wear",
           ylim=(0, 1.18 * top), xlim=(mu.min() / 1.5, mu.max() * 1.5),
           title=f"Ch. 7 rig, crank-rod joint lubricated ({FILM_WORDS[st['film']]}, σ = "
                 f"{1e6 * st['roughness_m']:g} µm): life against viscosity")
    ax.title.set_fontsize(9)
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def lubrication_slider_crank(path: Path) -> None:
    """The lubricated Table 2-1 slider-crank over one crank revolution
    (stored dynamic runs): the film parameter and the journal orbit."""
    plt = _pyplot()
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter

    d = read_csv(LUBRICATION / "slider_crank.csv")
    m = json.loads((LUBRICATION / "slider_crank.json").read_text())
    fig, (a, b) = plt.subplots(1, 2, figsize=(10.5, 5.4),
                               gridspec_kw={"width_ratios": [1.5, 1]})
    colors = ["tab:blue", "tab:orange"]
    for mu, color in zip(m["viscosities_Pa_s"], colors):
        tag = f"mu_{1e3 * mu:g}mPas"  # as design_studies/lubrication_figure_data.py
        a.plot(d["t_s"], d[f"{tag}_film_ratio"], color=color, lw=1.2, label=f"η = {mu:g} Pa s")
        b.plot(d[f"{tag}_x_over_c"], d[f"{tag}_y_over_c"], color=color, lw=1.1,
               label=f"η = {mu:g} Pa s")
    a.axhline(3.0, color="tab:red", ls="--", lw=1.0, label="λ = 3: onset of mixed lubrication")
    a.axhline(1.0, color="k", ls=":", lw=1.0, label="λ = 1: boundary")
    # a logarithmic axis down to lambda = 0.1; below it (and where lambda < 0:
    # the pin pressed past the mean surfaces into the asperities) the time is
    # shaded in the oil's colour instead of drawn
    floor = 0.1
    for mu, color in zip(m["viscosities_Pa_s"], colors):
        ratio = d[f"mu_{1e3 * mu:g}mPas_film_ratio"]
        below = ratio < floor
        if below.any():
            a.fill_between(d["t_s"], floor, 0.2, where=below, color=color, alpha=0.35,
                           step="mid", lw=0,
                           label=f"η = {mu:g} Pa s: λ < {floor:g} (asperity interference "
                                 f"down to λ = {ratio.min():.1f})")
    a.set_yscale("log")
    a.yaxis.set_major_locator(FixedLocator([0.1, 0.3, 1, 3, 10, 30, 100]))
    a.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    a.yaxis.set_minor_formatter(NullFormatter())
    a.set(xlabel="time [s] (one crank revolution, pin centred at t = 0)",
          ylabel="film parameter λ = h_min / σ", xlim=(0, m["duration_s"]), ylim=(floor, 130),
          title=f"Film parameter (σ = {1e6 * m['roughness_m']:g} µm, "
                f"c = {1e3 * m['clearance_m']:g} mm)")
    a.legend(fontsize=7, loc="upper left", bbox_to_anchor=(0.0, -0.16), ncol=1)
    reach = 1.0
    if "dry_x_over_c" in d:
        reach = float(np.max(np.hypot(d["dry_x_over_c"], d["dry_y_over_c"])))
        b.plot(d["dry_x_over_c"], d["dry_y_over_c"], color="0.45", lw=0.8, ls="--",
               label=f"dry (EFM): impacts, up to e/c = {reach:.1f}\n(the pin sinks into "
                     "the elastic layer)")
    circle = np.linspace(0.0, 2.0 * np.pi, 200)
    b.plot(np.cos(circle), np.sin(circle), color="k", lw=0.8, label="clearance circle")
    lim = 1.05 * max(reach, 1.0)
    b.set(aspect="equal", xlim=(-lim, lim), ylim=(-lim, lim), xlabel="x / c",
          ylabel="y / c", title="Journal orbit e / c in the bushing (rod frame)")
    b.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    for ax in (a, b):
        ax.grid(alpha=0.3)
    a.title.set_fontsize(9)
    b.title.set_fontsize(9)
    fig.suptitle(f"Table 2-1 slider-crank, crank-rod joint lubricated ({FILM_WORDS[m['film']]}; "
                 "dynamic model, Rodas4, rtol = atol = 1e-8)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def lubrication_four_bar_squeeze(path: Path) -> None:
    """The lubricated four-bar's minimum film over a crank cycle (stored
    quasi-static solves): the journal's orbit with the squeeze film against
    the steady balance at every sample, at two viscosities, over the joint's
    relative rotation (its reversals)."""
    plt = _pyplot()
    d = read_csv(LUBRICATION / "four_bar_squeeze.csv")
    sigma = 1.0  # um, as design_studies/lubrication_figure_data.py (FB_ROUGHNESS)
    fig, (a, b) = plt.subplots(2, 1, figsize=(8.0, 6.2), sharex=True,
                               gridspec_kw={"height_ratios": [2.2, 1]})
    crank = d["crank_angle_deg"]
    for mu, color in zip((0.5, 0.005), ("tab:blue", "tab:orange")):
        tag = f"mu_{1e3 * mu:g}mPas"
        a.plot(crank, d[f"{tag}_orbit_h_min_um"], color=color, lw=1.4,
               label=f"η = {mu:g} Pa s: orbit with the squeeze film")
        steady = d[f"{tag}_steady_h_min_um"]
        a.plot(crank, steady, color=color, lw=1.0, ls="--",
               label=f"η = {mu:g} Pa s: steady at every sample"
                     + (" (0 all cycle)" if np.max(steady) == 0.0 else ""))
    a.axhline(3.0 * sigma, color="tab:red", ls=":", lw=1.0,
              label=f"3σ = {3 * sigma:g} µm: onset of mixed lubrication")
    # where omega changes sign from the sample before (the cycle wraps round)
    sign = np.sign(d["omega_rad_s"])
    reversals = crank[sign != np.roll(sign, 1)]
    for ax in (a, b):
        for r in reversals:
            ax.axvline(r, color="0.6", lw=0.8)
        ax.grid(alpha=0.3)
    top = max(np.max(d[k]) for k in d if k.endswith("h_min_um"))
    a.set(ylabel="minimum film h_min [µm]", ylim=(0, 1.4 * top),
          title="Minimum film over the cycle (grey lines: the rotation reverses)")
    a.legend(fontsize=7, loc="upper right", ncol=2)
    b.plot(crank, d["omega_rad_s"], color="k", lw=1.0, label="ω pin − bushing")
    b.set(xlabel="crank angle [deg]", ylabel="ω [rad/s]", xlim=(0, 360))
    b.legend(fontsize=7, loc="upper right")
    a.title.set_fontsize(9)
    fig.suptitle(f"four_bar_wear, coupler-rocker joint in oil (finite-length film, σ = "
                 f"{sigma:g} µm, quasi-static model, unworn bushing)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def _short_over_finite_units(ld, eps):
    """The short and long films' steady loads in the finite film's stored
    units, 6 mu omega R^4 / c^2 (`reynolds_forces` per unit wedge): the short
    bearing's mu omega R L^3 / c^2 w_s is (4/3) (L/D)^3 w_s of them, the long
    bearing's mu omega R^3 L / c^2 w_l is (L/D) w_l / 3."""
    return (4.0 / 3.0) * ld**3 * _short_steady(eps)[0], ld * _long_steady(eps)[0] / 3.0


# What the validity map calls agreement: a film's steady load within 5 % of the
# finite film's (`film_law_for` keeps the short film within 4.5 %); 10 % drawn too.
MAP_TOLERANCE, MAP_LOOSE = 0.05, 0.10
# The lubricated mechanisms' joints on the map: L/D and radial clearance from
# their files (rig_lubricated.toml: thesis Tables 7-1, 7-2; four_bar_lubricated.toml),
# the eps range from their stored runs (design_studies/lubrication_figure_data.py).
MAP_JOINTS = (("rig", "crank_rod", 13.1 / 19.0, 33.0, "s", "tab:red",
               "Ch. 7 rig, crank-rod joint: L/D = 13.1/19"),
              ("four_bar", "coupler_rocker", 10.0 / 12.0, 50.0, "D", "tab:green",
               "four-bar, coupler-rocker joint: L/D = 10/12"))


def _run_eccentricities(folder: str, joint: str, c_um: float) -> tuple[float, float]:
    """A stored file run's eps range on the unworn bore: from its thickest
    film (the worn groove widens the gap past c) up to the film's saturation
    1 - sigma / c, where the mixed law holds the film once the asperities
    carry the rest (a point where the film is saturated all cycle)."""
    run = json.loads((LUBRICATION / folder / "summary.json").read_text())
    film = read_csv(LUBRICATION / folder / f"film_{joint}.csv")
    saturation = 1.0 - run["joints"][joint]["lubricant"]["roughness_um"] / c_um
    return min(float(np.min(1.0 - film["h_min_um"] / c_um)), saturation), saturation


def lubrication_validity_map(path: Path) -> None:
    """Where the short and the long film carry the finite film's steady load
    to 5 % (10 %), over L/D and eps, from the stored Reynolds solves; the
    analytic criterion of `film_law_for`; the lubricated rig's and four-bar's
    joints."""
    plt = _pyplot()
    from matplotlib.patches import PathPatch

    from diffwear.contact.finite_bearing import SHORT_BEARING_LIMIT

    d = read_csv(LUBRICATION / "validity_map.csv")
    lds, epss = np.unique(d["length_over_diameter"]), np.unique(d["eps"])
    grid = np.full((len(epss), len(lds)), np.nan)
    for ld, eps, load in zip(d["length_over_diameter"], d["eps"], d["load"]):
        grid[np.searchsorted(epss, eps), np.searchsorted(lds, ld)] = load
    ld_g, eps_g = np.meshgrid(lds, epss)
    short, long = _short_over_finite_units(ld_g, eps_g)
    short_err, long_err = np.abs(short / grid - 1.0), np.abs(long / grid - 1.0)
    fig, ax = plt.subplots(figsize=(8.0, 6.4))
    # underneath: where neither closed form is within 5 %
    ax.axhspan(0.0, 1.0, color="#e5e5e5", zorder=0, label="only the finite film within 5 %")
    # each region and line traced by matplotlib's contouring, then drawn as a
    # labelled patch and lines (contour sets have no legend entry of their own)
    for err, color, fill, name in ((short_err, "tab:blue", "#9ecae1", "short"),
                                   (long_err, "tab:orange", "#fdd0a2", "long")):
        area = ax.contourf(ld_g, eps_g, err, levels=[0.0, MAP_TOLERANCE])
        for k, outline in enumerate(area.get_paths()):
            if len(outline.vertices):
                ax.add_patch(PathPatch(
                    outline, facecolor=fill, lw=0, zorder=1,
                    label=f"{name} film within 5 % of the finite film" if k == 0 else None))
        area.remove()
        edge = ax.contour(ld_g, eps_g, err, levels=[MAP_LOOSE])
        for k, segment in enumerate(piece for outline in edge.get_paths()
                                    for piece in outline.to_polygons(closed_only=False)):
            ax.plot(segment[:, 0], segment[:, 1], color=color, ls=":", lw=1.3, zorder=2,
                    label=f"{name} film 10 % off the finite film" if k == 0 else None)
        edge.remove()
    eps_line = np.linspace(0.0, 1.0, 200)
    ax.plot(np.sqrt(SHORT_BEARING_LIMIT * (1.0 - eps_line)), eps_line, color="k", lw=1.6,
            label=f"criterion (L/D)² = {SHORT_BEARING_LIMIT:g} (1 − ε): short film left of it")
    for folder, joint, ld, c_um, marker, color, words in MAP_JOINTS:
        lo, hi = _run_eccentricities(folder, joint, c_um)
        span = (f"ε = {hi:.2f} all cycle (its run: the film saturated)" if lo == hi
                else f"ε {lo:.2f}–{hi:.2f} (its run, its saturation)")
        ax.plot([ld, ld], [lo, hi], color=color, lw=3.0, marker=marker, ms=6,
                label=f"{words}, {span}")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.11), ncol=2)
    # from the smallest eps solved (at eps = 0 the steady load vanishes)
    ax.set(xscale="log", xlim=(lds[0], lds[-1]), ylim=(epss[0], 1.0),
           xlabel="length-to-diameter ratio L/D [-]", ylabel="eccentricity ratio ε [-]",
           title="Where the short and long films carry the finite (Reynolds) film's "
                 "steady load")
    ax.title.set_fontsize(10)
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def lubrication_raimondi_boyd(path: Path) -> None:
    """The finite film's Sommerfeld number and attitude angle (stored) at
    L/D = 1/4, 1/2, 1 against Raimondi & Boyd's table, with the short and the
    long (half-Sommerfeld) films' closed forms."""
    plt = _pyplot()
    from diffwear.contact.raimondi_boyd import RAIMONDI_BOYD

    d = read_csv(LUBRICATION / "raimondi_boyd.csv")
    line = np.linspace(0.03, 0.97, 300)
    short_load, short_phi = _short_steady(line)
    long_load, long_phi = _long_steady(line)
    fig, (a, b) = plt.subplots(1, 2, figsize=(10.5, 4.2))
    names = {0.25: "1/4", 0.5: "1/2", 1.0: "1"}
    for (ld, table), color in zip(sorted(RAIMONDI_BOYD.items()),
                                  ("tab:blue", "tab:orange", "tab:green")):
        mine = d["length_over_diameter"] == ld
        eps_t = np.array(sorted(table))
        s_t = np.array([table[e][0] for e in eps_t])
        phi_t = np.array([table[e][1] for e in eps_t])
        a.plot(d["eps"][mine], d["sommerfeld"][mine], color=color, lw=1.4,
               label=f"L/D = {names[ld]}: finite film")
        a.plot(eps_t, s_t, "o", color=color, mfc="none", ms=6,
               label=f"L/D = {names[ld]}: Raimondi & Boyd")
        # S = (R / c)^2 mu N / P of the short film: 1 / (4 pi (L/D)^2 w_s)
        a.plot(line, 1.0 / (4.0 * np.pi * ld**2 * short_load), color=color, lw=1.0, ls="--",
               label=f"L/D = {names[ld]}: short film")
        b.plot(d["eps"][mine], d["attitude_deg"][mine], color=color, lw=1.4,
               label=f"L/D = {names[ld]}: finite film")
        b.plot(eps_t, phi_t, "o", color=color, mfc="none", ms=6,
               label=f"L/D = {names[ld]}: Raimondi & Boyd")
    # the long film's S = 1 / (pi w_l), whatever L/D
    a.plot(line, 1.0 / (np.pi * long_load), color="k", lw=1.0, ls=":",
           label="long film (any L/D)")
    b.plot(line, short_phi, color="0.3", lw=1.0, ls="--", label="short film (any L/D)")
    b.plot(line, long_phi, color="k", lw=1.0, ls=":", label="long film (any L/D)")
    a.set(yscale="log", xlim=(0, 1), ylim=(1e-3, 100), xlabel="eccentricity ratio ε [-]",
          ylabel="Sommerfeld number S = (R/c)² ηN / P [-]", title="Sommerfeld number")
    b.set(xlim=(0, 1), ylim=(0, 95), xlabel="eccentricity ratio ε [-]",
          ylabel="attitude angle φ [deg]", title="Attitude angle")
    a.legend(fontsize=6.5, loc="lower left", ncol=2)
    b.legend(fontsize=6.5, loc="lower left")
    for ax in (a, b):
        ax.grid(alpha=0.3, which="both")
    fig.suptitle("Finite film against Raimondi & Boyd's full journal bearing (Reynolds "
                 "cavitation); short and half-Sommerfeld long films", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=DPI)
    plt.close(fig)


def lubrication_rig_film(path: Path) -> None:
    """``film_crank_rod.png`` of the stored ``diffwear run rig_lubricated
    --cycles 21400``, drawn by `diffwear.plots.film_panels` from its
    ``film_crank_rod.csv``."""
    from diffwear.contact.mixed import ONSET_FILM_RATIO
    from diffwear.plots import film_panels

    folder = LUBRICATION / "rig"
    s = json.loads((folder / "summary.json").read_text())
    joint = s["joints"]["crank_rod"]
    f = read_csv(folder / "film_crank_rod.csv")
    sigma = joint["lubricant"]["roughness_um"] * 1e-6
    cycles = joint["cycles"]
    film_panels(path, f["crank_angle_deg"],
                {"unworn bushing": (f["h_min_um"] * 1e-6, f["asperity_share"],
                                    f["interference_um"] * 1e-6),
                 f"worn, {cycles:,.0f} cycles": (f["h_min_um_worn"] * 1e-6,
                                                 f["asperity_share_worn"],
                                                 f["interference_um_worn"] * 1e-6)},
                onset=ONSET_FILM_RATIO * sigma, onset_ratio=ONSET_FILM_RATIO, roughness=sigma,
                title=f"rig_lubricated, crank-rod joint (η = "
                      f"{joint['lubricant']['viscosity_Pa_s'] * 1e3:.3g} mPa s, σ = "
                      f"{joint['lubricant']['roughness_um']:g} µm): quasi-static orbit "
                      "over the cycle, unworn and worn bushing")


FIGURES: dict[str, Callable[[Path], None]] = {
    "figures/results_against_thesis.png": results_against_thesis,
    "figures/ch2_ideal_reaction.png": ideal_reaction,
    "figures/ch3_clearance_forces.png": clearance_forces,
    "figures/ch3_clearance_loci.png": clearance_loci,
    "figures/ch4_pin_pivot_history.png": pin_pivot_history,
    "figures/ch4_pin_pivot_profiles.png": pin_pivot_profiles,
    "figures/ch5_wear_5000_profile.png": wear_5000_against_thesis,
    "figures/ch5_wear_5000_history.png": wear_study("wear-5000", "wear_history.png"),
    "figures/ch7_rig_against_thesis.png": rig_profile_against_thesis,
    "figures/ch7_rig_profile.png": wear_study("rig-21400", "wear_profile.png"),
    "figures/ch7_rig_history.png": wear_study("rig-21400", "wear_history.png"),
    "figures/ch7_rig_locus_and_force.png": wear_study("rig-21400",
                                                      "contact_locus_and_force.png"),
    "figures/ch7_rig_joint_force.png": rig_joint_force,
    "figures/ch8_life_map_joint1.png": life_map(1),
    "figures/ch8_life_map_joint2.png": life_map(2),
    "figures/quasi_static_agreement.png": agreement,
    "figures/performance_costs.png": performance_costs,
    "figures/rig_sweep_max_depth.png": rig_sweep_heatmap("max_depth_mm"),
    "figures/rig_tornado_max_depth.png": rig_tornado("max_depth_mm"),
    "figures/rig_tornado_volume.png": rig_tornado("volume_mm3"),
    "figures/lubrication_short_bearing.png": lubrication_short_bearing,
    "figures/lubrication_sommerfeld.png": lubrication_sommerfeld,
    "figures/lubrication_life_viscosity.png": lubrication_life_viscosity,
    "figures/lubrication_slider_crank.png": lubrication_slider_crank,
    "figures/lubrication_rig_film.png": lubrication_rig_film,
    "figures/lubrication_raimondi_boyd.png": lubrication_raimondi_boyd,
    "figures/lubrication_validity_map.png": lubrication_validity_map,
    "figures/lubrication_four_bar_squeeze.png": lubrication_four_bar_squeeze,
}


def draw_all(folder: Path) -> dict[str, Path]:
    """Draw every figure into ``folder`` (each in its own subfolder: some plot
    functions write companion files); site path -> file."""
    drawn = {}
    for site_path, draw in FIGURES.items():
        target = folder / site_path.replace("/", "__")
        target.mkdir(parents=True, exist_ok=True)
        path = target / Path(site_path).name
        draw(path)
        drawn[site_path] = path
    return drawn


if __name__ == "__main__":
    import time

    out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/docs-figures")
    t0 = time.perf_counter()
    for site_path, path in draw_all(out).items():
        print(f"{site_path}: {path.stat().st_size / 1e3:.0f} kB")
    print(f"{time.perf_counter() - t0:.1f} s")
