"""The wear studies on the quasi-static model (``--model quasi-static``).

Same outputs as the dynamic route where they have a meaning (profile, history,
joint force and pin locus over the first and the last cycle, report, plots):
the history has one row per step of the wear ODE in the cycle count, the
force is the ideal mechanism's, the locus the pin's equilibrium.
"""

from __future__ import annotations

import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..contact import ContactHistory, MixedLubrication
from ..mechanism.geometry import safe_angle
from ..presets import PTFE_DENSITY, WearJointDesign
from ..quasistatic import QuasiStatic
from ..report import Bullets, Report
from ..wear import worn_volume
from ..wear.status import STATUS_OK, STATUS_TEXT
from ._report import COMPARISON_WORDS, comparison_table, peak_line, write_report

JOINT = "crank_rod"


@eqx.filter_jit
def _history(model: QuasiStatic, mech, y0, period, depth) -> ContactHistory:
    """The joint over one cycle at wear ``depth``: loads of the ideal
    mechanism, the pin at equilibrium."""
    loads = model.loads(mech, (JOINT,), y0, period).joints[0]
    joint = model.joints(mech, (JOINT,))[0]
    eq = joint.equilibrium(depth, loads)
    c = joint.clearance + depth
    gap = eq.offset @ joint.directions.T - c
    angle = jnp.mod(safe_angle(eq.offset), 2 * jnp.pi)
    return ContactHistory(force=loads.force, normal_load=eq.normal_load, offset=eq.offset,
                          penetration=gap.max(axis=1), contact_angle=angle,
                          pressure=eq.pressure)


def run(out, *, name, mech, design: WearJointDesign, y0, cycles, period, thesis: dict,
        description: str, log, extra_summary=None, extra_report=(),
        model: QuasiStatic | None = None) -> dict:
    from ..plots import wear as plots_wear

    model = QuasiStatic() if model is None else model
    el = mech.element(JOINT)
    log(f"[{name}] {cycles} cycles, quasi-static model (steps {model.steps}, "
        f"{model.samples} load samples per cycle) ...")

    def evolve(m):
        return model.evolve(m, (JOINT,), y0, period=period, cycles=float(cycles),
                            wall_thickness=design.wall)

    t0 = time.perf_counter()
    compiled = jax.jit(evolve).lower(mech).compile()
    compile_time = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = jax.block_until_ready(compiled(mech))
    wall_time = time.perf_counter() - t0

    theta = np.asarray(el.profile.theta)
    depth = np.asarray(res.depth[0])
    hist = res.history[0]
    valid = np.asarray(hist.valid)
    steps_n = np.asarray(hist.cycles)[valid]
    steps_depth = np.asarray(hist.depth)[valid]
    volumes = np.asarray(worn_volume(steps_depth, el.bushing_radius, el.law.depth)) * 1e9
    volume = float(worn_volume(depth, el.bushing_radius, el.law.depth)) * 1e9
    first = _history(model, mech, y0, period, jnp.zeros_like(depth))
    last = _history(model, mech, y0, period, jnp.asarray(depth))
    crank = 2 * np.pi * np.arange(model.samples) / model.samples

    out.csv("wear_profile.csv", {"theta_rad": theta, "depth_mm": depth * 1e3})
    out.csv("wear_history.csv", {"cycles": steps_n, "max_depth_mm": steps_depth.max(axis=1) * 1e3,
                                 "volume_mm3": volumes})
    for tag, h in (("first", first), ("last", last)):
        f = np.asarray(h.force)
        out.csv(f"joint_force_{tag}_cycle.csv", {
            "crank_angle_rad": crank, "fx_N": f[:, 0], "fy_N": f[:, 1],
            "force_N": np.hypot(f[:, 0], f[:, 1]), "normal_load_N": np.asarray(h.normal_load)})
        off = np.asarray(h.offset)
        out.csv(f"contact_locus_{tag}_cycle.csv", {
            "crank_angle_rad": crank, "offset_x_mm": off[:, 0] * 1e3,
            "offset_y_mm": off[:, 1] * 1e3, "contact_angle_rad": np.asarray(h.contact_angle),
            "penetration_um": np.asarray(h.penetration) * 1e6})
    figs = plots_wear.wear_figures(out, name=name, theta=theta, depth_mm=depth * 1e3,
                                   history=(steps_n[1:], steps_depth.max(axis=1)[1:] * 1e3,
                                            volumes[1:]),
                                   crank=crank, first=first, last=last,
                                   clearance_mm=float(design.clearance) * 1e3, thesis=thesis,
                                   label="diffwear (quasi-static)", markers="wear ODE steps",
                                   wall_mm=float(design.wall) * 1e3, status=int(res.status))
    status = int(res.status)
    margin, margin_worn = float(res.contact_margin[0]), float(res.contact_margin_worn[0])
    summary = {
        "study": name, "model": "quasi-static", "cycles": float(res.cycles),
        "cycles_requested": float(cycles),
        "max_wear_depth_mm": float(depth.max()) * 1e3, "wear_volume_mm3": volume,
        "max_wear_angle_rad": float(theta[np.argmax(depth)]),
        "worn_mass_g": volume * 1e-9 * PTFE_DENSITY * 1e3,
        "status": status, "status_text": STATUS_TEXT[status],
        "contact_margin": margin, "contact_margin_worn": margin_worn,
        "wear_steps": int(valid.sum()) - 1, "load_samples_per_cycle": model.samples,
        "dynamic_cycles_simulated": 0,
        "mean_joint_force_first_cycle_N": float(np.mean(np.asarray(first.force_magnitude))),
        "mean_normal_load_first_cycle_N": float(np.mean(np.asarray(first.normal_load))),
        "n_theta": int(depth.size), "wall_time_s": wall_time, "compile_time_s": compile_time,
        "thesis": thesis, **(extra_summary or {})}
    summary["files"] = sorted(set(out.files)) + ["report.md", "summary.json"]
    warnings = []
    if margin_worn < 1.0:
        warnings.append(f"warning: at the final profile the load may not hold the pin on the "
                        f"wall where it turns fastest (contact margin {margin_worn:.2f} < 1); "
                        "check with the dynamic model (--model dynamic)")
    report = Report(name, [
        description,
        "Model: quasi-static joint (the pin at the equilibrium of "
        + ("the oil film and the asperities (the EFM springs at the summit height)"
           if isinstance(el.law, MixedLubrication) else "the EFM springs")
        + " under the ideal mechanism's joint load; wear integrated in the cycle count).",
        comparison_table("diffwear (quasi-static)", summary, thesis),
        COMPARISON_WORDS,
        Bullets([
            f"cycles: {summary['cycles']:.0f} in {summary['wear_steps']} steps of the wear ODE "
            "(the profile's growth integrated over the cycle count by an adaptive solver); "
            f"status: {STATUS_TEXT[status]}",
            peak_line(summary),
            f"contact margin: unworn {margin:.3g}, final profile {margin_worn:.3g}.  The "
            "smallest over the cycle of the joint load divided by m c omega^2, the inward "
            "force the pin (effective mass m) needs to follow the load around a wall of "
            "clearance c as the load turns at omega: above 1 the load holds the pin on the "
            "wall, below 1 the pin may fly across the clearance and this model does not hold; "
            "a huge value means the load's direction hardly turns",
            f"mean |joint force| {summary['mean_joint_force_first_cycle_N']:.1f} N (the "
            "magnitude of the joint's load averaged over a cycle); mean total normal load "
            f"(unworn) {summary['mean_normal_load_first_cycle_N']:.1f} N (the bushing's "
            "pressure integrated over the contact arc, averaged over a cycle: above the joint "
            "force because the pressure spreads over an arc)",
            "the first- and last-cycle joint force curves (joint_force_first/last_cycle.csv, "
            "contact_locus_and_force.png) are the same: this model takes the joint load from "
            "the ideal mechanism, which the wear does not change; the normal load and the "
            "pin's locus do change with the worn profile",
            f"run time {wall_time:.2f} s (the compiled wear evolution), compile time "
            f"{compile_time:.1f} s (compiling it)",
            *warnings]),
        *extra_report])
    write_report(out, report, figs, summary)
    log(f"[{name}] quasi-static: max depth {summary['max_wear_depth_mm']:.4f} mm, volume "
        f"{volume:.2f} mm^3, {wall_time:.2f} s (+{compile_time:.1f} s compile)")
    for w in warnings:
        log(f"[{name}] {w[2:]}")
    if status != STATUS_OK:
        from ..errors import SolverError

        raise SolverError(f"{name}: {STATUS_TEXT[status]} after {summary['cycles']:.0f} cycles "
                          f"(max depth {summary['max_wear_depth_mm']:.4f} mm; quasi-static "
                          f"model); stopped, results so far written to {out.path}")
    return summary
