"""The FEM wear route (`diffwear.wear.fem_route`): FE contact pressure from the
dynamics' joint force, checked against independent values: the EFM route's
exact increment in the thin-wall (Winkler) limit, a finer time quadrature,
the Archard volume, M = 1 geometry refreshes, central differences.

Small sizes throughout: the rig mechanism with a 72-node profile grid (5 deg),
one dynamic cycle saved at 129 times and reused by every test."""


import jax

jax.config.update("jax_enable_x64", True)

import equinox as eqx  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from diffwear import cli  # noqa: E402
from diffwear.cli.objects import check_contact  # noqa: E402
from diffwear.errors import InputError  # noqa: E402
from diffwear.presets import (  # noqa: E402
    RIG_JOINT,
    TABLE_7_1,
    WearJointDesign,
    rig_slider_crank,
    with_wear_joint,
)
from diffwear.studies import _wear_common as common  # noqa: E402
from diffwear.studies.rig_21400 import PERIOD  # noqa: E402
from diffwear.wear import CycleSettings, wear_cycle, worn_volume  # noqa: E402
from diffwear.wear import fem_route as fr  # noqa: E402

N = 72  # profile grid = FE inner-surface nodes (5 deg)
SAMPLES = 128  # quadrature intervals of the saved cycle (subsampled below)
JOINT = "crank_rod"
BORE = float(RIG_JOINT.bushing_radius)
# Thin wall: b - a = 0.05 a (tests/test_fem.py: the ring's contact is then within
# 0.03 % of the Winkler foundation's peak pressure).
THIN = WearJointDesign(RIG_JOINT.k, RIG_JOINT.clearance, RIG_JOINT.depth, RIG_JOINT.diameter,
                       wall=0.05 * BORE, mu=RIG_JOINT.mu, restitution=RIG_JOINT.restitution)


@pytest.fixture(scope="module")
def thin_cycle():
    """The rig with a thin-walled EFM bushing: one warm-up cycle, then one
    cycle saved at SAMPLES + 1 times (its EFM increment integrated exactly)."""
    mech0, q_guess = rig_slider_crank(TABLE_7_1)
    mech = with_wear_joint(mech0, THIN, n_theta=N)
    y0 = common.initial_state(mech0, q_guess, mech)
    cyc = jax.jit(lambda y, t: wear_cycle(mech, JOINT, y, t, PERIOD, n_save=SAMPLES + 1))
    warm = cyc(y0, 0.0)
    r = cyc(warm.y_end, PERIOD)
    assert bool(warm.ok) and bool(r.ok)
    return mech, r


def _increment(mech, r, model, step=1, depth=None):
    el = mech.element(JOINT)
    depth = jnp.zeros(N) if depth is None else depth
    cmat = fr.ring_compliance(model, el.bushing_radius, depth)
    contact = fr.ring_contact(cmat, fr.unworn_tributary(model, el.bushing_radius, N),
                              el.bushing_radius, el.pin_radius, depth, el.law.depth)
    s = fr.joint_samples(mech, JOINT, r.ys[::step], model.force)
    return fr.fem_increment(contact, s, r.ts[::step], el.wear.coefficient)


def test_thin_wall_increment_approaches_efm_exact(thin_cycle):
    """Winkler limit: with b - a = 0.05 a the ring is an elastic foundation of
    modulus E_W / (b - a), the EFM of the dynamics.  With the normal part of the
    joint force (the EFM's spring loads), the FE increment of the cycle must
    approach the EFM route's exact (ODE-integrated) increment.  Differences
    left: the EFM's spring damping (its pressure shape carries tau d(delta)/dt,
    the FE spreads the same load elastically), the ray gap vs the linearised
    one, Simpson-lumped loads and the 64-interval quadrature, and the contact
    edges on the 5 deg grid.  Measured: peak +1.8 %, volume +0.7 %, total
    normal load x sliding +0.12 %, largest pointwise difference 5.7 % of the
    peak (at the contact edges); tolerances 3 %, 1.5 %, 0.5 %, 8 %."""
    mech, r = thin_cycle
    model = fr.FemWearModel(0.5e9, 0.38, BORE + float(THIN.wall), n_layers=2, force="normal")
    inc = _increment(mech, r, model, step=2)
    efm = np.asarray(r.depth_increment)
    dh = np.asarray(inc.depth_increment)
    assert bool(inc.ok)
    assert abs(dh.max() / efm.max() - 1) < 3e-2
    assert abs(dh.sum() / efm.sum() - 1) < 1.5e-2
    assert abs(float(inc.load_sliding) / float(r.load_sliding) - 1) < 5e-3
    assert np.argmax(dh) == np.argmax(efm)
    assert np.max(np.abs(dh - efm)) < 8e-2 * efm.max()  # the whole profile, contact edges incl.


def test_samples_converge_and_volume_is_archard(thin_cycle):
    """The rig's own (thick) PTFE ring under the same cycle: doubling the samples
    from 32 to 64 to 128 intervals changes the increment by < 4e-3 of its peak
    (measured 6e-4 .. 2.8e-3 against 128, not monotone in the samples (16: 1.1e-3,
    32: 2.8e-3, 64: 1.1e-3 on one build): the node-wise motion of the contact
    edge leaves a floor that does not shrink at second order, and where an edge
    node falls moves with the last bits of the stiff cycle).  The increment's
    volume d R_b sum dh dtheta equals k x the FE total normal load x sliding,
    sum_i w_i (L sum_j f_j) R_b |omega|, to the quadrature difference of the
    nodal pressures (rectangle rule vs Simpson loads; measured 2.8e-3 on this
    5 deg grid, 7e-4 on the study's 2 deg grid; tolerance 6e-3)."""
    mech, r = thin_cycle
    model = fr.default_model(RIG_JOINT)
    inc = {s: _increment(mech, r, model, step=SAMPLES // s) for s in (32, 64, 128)}
    ref = np.asarray(inc[128].depth_increment)
    for s in (32, 64):
        assert bool(inc[s].ok)
        assert np.max(np.abs(np.asarray(inc[s].depth_increment) - ref)) < 4e-3 * ref.max(), s
    el = mech.element(JOINT)
    vol = float(worn_volume(inc[128].depth_increment, el.bushing_radius, el.law.depth))
    archard = float(el.wear.coefficient * inc[128].load_sliding)
    assert abs(vol / archard - 1) < 6e-3
    # an independent load: the thin-walled EFM's total normal load over the same
    # cycle; the thick ring spreads the same joint force over a wider arc, so its
    # normal load is larger (measured +4.3 %; the resultant's friction part adds
    # at most sqrt(1 + 0.13^2) - 1 = 0.8 %); tolerance 6 %
    assert 0 < float(inc[128].load_sliding) / float(r.load_sliding) - 1 < 6e-2


def test_gradient_wrt_youngs_modulus_matches_central_difference(thin_cycle):
    """d(peak increment)/dE through the FE contact's implicit derivative, at a
    tiny size (16 intervals), against a central difference (relative step 1e-4)."""
    mech, r = thin_cycle
    el = mech.element(JOINT)
    k = el.wear.coefficient

    @jax.jit
    def increment(e):
        model = fr.FemWearModel(e, 0.38, BORE + float(RIG_JOINT.wall), n_layers=2)
        return _increment(mech, r, model, step=8).depth_increment / k  # [m per (1/Pa)]

    e0 = 0.5e9
    j = int(np.argmax(increment(e0)))  # node of the peak

    @jax.jit
    def peak(e):
        return increment(e)[j]

    g = float(jax.grad(peak)(e0))
    h = 1e-4 * e0
    fd = (float(peak(e0 + h)) - float(peak(e0 - h))) / (2 * h)
    assert abs(fd) > 0
    assert abs(g / fd - 1) < 1e-4


@pytest.mark.long  # two short FEM-route evolutions, ~25 s
def test_refresh_interval_agrees_with_every_cycle_rebuild():
    """M = 1 (compliance rebuilt every wear cycle) against M = 3 (built once from
    the unworn ring; wear enters only through the gap) over 3 wear cycles of
    A = 3,000 (0.24 mm of wear on the rig's thick ring, half the full run's
    depth): measured relative differences 1.8e-4 (max depth) and 5.6e-4
    (volume; 1.9e-4 and 2.6e-4 with J from 8 of the 32 samples), tolerance
    2e-3.  Also the volume bookkeeping of the evolution: the
    worn volume in the FE's own quadrature (the unworn ring's tributary lengths:
    Simpson weights) = k x A-weighted sum of (FE normal load x sliding) to
    round-off; the rectangle rule of `worn_volume` differs from it by the
    quadrature of a contact pressure on 72 nodes (measured 7.5e-3 and 7.7e-3
    here, -7.7e-3 after 900 cycles, 2.8e-3 with A = 300), tolerance 1e-2."""
    mech0, q_guess = rig_slider_crank(TABLE_7_1)
    mech = with_wear_joint(mech0, RIG_JOINT, n_theta=N)
    y0 = common.initial_state(mech0, q_guess, mech)
    base = fr.default_model(RIG_JOINT, n_samples=32)

    @jax.jit
    def run(m):
        model = fr.FemWearModel(base.youngs_modulus, base.poisson_ratio, base.outer_radius,
                                refresh_interval=m, n_samples=32)
        return fr.evolve_fem(mech, JOINT, y0, 9000, period=PERIOD, fem=model,
                             extrapolation=3000.0, cycle=CycleSettings(1e-5, 1e-5))

    el = mech.element(JOINT)
    out = {}
    for m in (1.0, 3.0):
        res = run(jnp.asarray(m))
        res.check("FEM route test")
        depth = res.depth[0]
        vol = float(worn_volume(depth, el.bushing_radius, el.law.depth))
        out[m] = (float(depth.max()), vol)
        archard = float(el.wear.coefficient * res.state.load_sliding[0])
        w0 = fr.unworn_tributary(base, el.bushing_radius, N)
        assert float(el.law.depth * jnp.sum(depth * w0)) / archard == pytest.approx(1, abs=1e-9)
        assert abs(vol / archard - 1) < 1e-2
    assert out[1.0][0] > 2e-4  # real wear: > 0.2 mm (measured 0.241 mm)
    assert abs(out[3.0][0] / out[1.0][0] - 1) < 2e-3
    assert abs(out[3.0][1] / out[1.0][1] - 1) < 2e-3


@pytest.mark.parametrize("kwargs, match", [
    (dict(refresh_interval=0), "refresh_interval"),
    (dict(refresh_interval=2.5), "refresh_interval"),
    (dict(n_samples=1), "n_samples"),
    (dict(force="shear"), "force must be one of"),
])
def test_bad_fem_route_input(kwargs, match):
    with pytest.raises(InputError, match=match):
        fr.default_model(RIG_JOINT, **kwargs)


@pytest.fixture(scope="module")
def rig_samples():
    """The rig (its own thick PTFE bushing, 72-node grid) after a warm-up
    cycle: one cycle's 65 samples by Tsit5 at rtol 1e-9 (reference), and by
    Rodas4 at its preset rtol 1e-4 stepped onto the samples (the FEM route's
    cycle) and interpolated between its steps (what the route no longer does)."""
    from diffwear.dynamics import Rodas4
    from diffwear.wear.cycle import cycle_integrator

    mech0, q_guess = rig_slider_crank(TABLE_7_1)
    mech = with_wear_joint(mech0, RIG_JOINT, n_theta=N)
    y0 = common.initial_state(mech0, q_guess, mech)
    warm = jax.jit(lambda y: wear_cycle(mech, JOINT, y, 0.0, PERIOD))(y0)
    solver, tol = cycle_integrator("rodas4")
    assert isinstance(solver, Rodas4)
    route_solver = fr.sampling_solver(solver)

    def cycle(solver, tol, step):
        return jax.jit(lambda y: wear_cycle(mech, JOINT, y, PERIOD, PERIOD, n_save=65,
                                            rtol=tol, atol=tol, solver=solver,
                                            step_to_saves=step))(warm.y_end)

    out = {"ref": cycle(None, 1e-9, True), "rodas4": cycle(route_solver, tol, True),
           "rodas4 interpolated": cycle(solver, tol, False)}
    assert all(bool(r.ok) for r in out.values())
    return mech, out


def test_rodas4_cycle_stepped_onto_the_samples_gives_the_tsit5_increment(rig_samples):
    """The FEM route's cycle on Rodas4 (rtol 1e-4) steps onto its 65 sample
    times, so each sampled joint force is a step end: one cycle's FE increment
    against Tsit5 at rtol 1e-9 on the rig's thick ring (72-node grid).
    Measured: peak 4.3e-4, largest nodal difference 6.1e-4 of the peak, total
    6.3e-4, sampled force 2.0e-2 of its peak; tolerances 2e-3, 2.5e-3, 2e-3,
    4e-2.  Interpolated between Rodas4's ~10 ms steps instead, the samples
    miss the stiff contact (measured: force 7.2e-2, nodal 9.4e-3, total
    7.7e-3): asserted > 5e-2, 5e-3, 4e-3, so the test fails if the cycle
    stops stepping onto the samples."""
    mech, cyc = rig_samples
    model = fr.default_model(RIG_JOINT)
    inc = {k: _increment(mech, r, model) for k, r in cyc.items()}
    ref = np.asarray(inc["ref"].depth_increment)
    force_ref = np.asarray(fr.joint_samples(mech, JOINT, cyc["ref"].ys).force)
    peak_force = np.max(np.linalg.norm(force_ref, axis=1))

    def errors(key):
        dh = np.asarray(inc[key].depth_increment)
        force = np.asarray(fr.joint_samples(mech, JOINT, cyc[key].ys).force)
        return (abs(dh.max() / ref.max() - 1), np.max(np.abs(dh - ref)) / ref.max(),
                abs(dh.sum() / ref.sum() - 1),
                np.max(np.linalg.norm(force - force_ref, axis=1)) / peak_force)

    peak, node, total, force = errors("rodas4")
    assert bool(inc["rodas4"].ok)
    assert peak < 2e-3 and node < 2.5e-3 and total < 2e-3 and force < 4e-2
    assert np.array_equal(np.asarray(cyc["rodas4"].ts), np.asarray(cyc["ref"].ts))
    _, node_i, total_i, force_i = errors("rodas4 interpolated")
    assert node_i > 5e-3 and total_i > 4e-3 and force_i > 5e-2
    # stepping onto 65 times costs steps (measured ~2.5x on the rig at 180 nodes)
    assert int(cyc["rodas4"].num_steps) > int(cyc["rodas4 interpolated"].num_steps)


def test_fem_route_takes_rodas4_and_drops_its_dense_output():
    """Rodas4 is taken (it was refused while the samples were interpolated);
    the route's cycles step onto the samples, so the Rosenbrock dense output
    (one more right-hand side per step) is dropped; Tsit5 (None) stays."""
    from diffwear.dynamics import ConstraintProjection, Rodas4

    mech0, q_guess = rig_slider_crank(TABLE_7_1)
    mech = with_wear_joint(mech0, RIG_JOINT, n_theta=N)
    model = fr.default_model(RIG_JOINT)
    ev = fr.FemEvolver(mech, JOINT, 100, fem=model, period=PERIOD,
                       cycle=CycleSettings(solver=Rodas4()))
    # traced as the study traces it, the mechanism and ring concrete (closed
    # over, not arguments): the route's branches are not hashed with them
    y0 = common.initial_state(mech0, q_guess, mech)
    out = jax.eval_shape(lambda y: ev.solve(y, slots=1), y0)
    assert out.depth[0].shape == (N,)
    assert isinstance(ev.term.settings.solver, Rodas4)
    assert ev.term.settings.solver.dense_output is False
    assert fr.FemEvolver(mech, JOINT, 100, fem=model, period=PERIOD).term.settings.solver is None
    wrapped = fr.sampling_solver(ConstraintProjection(Rodas4()))
    assert wrapped.solver.dense_output is False
    assert model.jacobian_samples == model.n_samples  # J from every sample by default
    assert fr.default_model(RIG_JOINT, jacobian_samples=8).jacobian_samples == 8


def test_window_and_warm_start_solve_the_same_contact(thin_cycle):
    """The FE solves of the route (`fem_increment`): each sample from the
    previous one's solution, on the half ring around F first.  The same
    solution as a cold whole-ring solve, sample by sample (pressures within
    1e-9 of the peak); a window too small for the contact falls back to the
    whole ring and still finds it; a start at the solution takes no Newton
    step; the closed-form Newton Jacobian and depth derivative (the implicit
    step's J) equal forward-mode autodiff."""
    from diffwear.fem import contact as fc

    mech, r = thin_cycle
    model = fr.default_model(RIG_JOINT)
    el = mech.element(JOINT)
    depth = 2e-4 * (1.0 + np.cos(2 * np.pi * np.arange(N) / N - np.pi))  # a worn pocket
    depth = jnp.asarray(depth)
    cmat = fr.ring_compliance(model, el.bushing_radius, depth)
    contact = fr.ring_contact(cmat, fr.unworn_tributary(model, el.bushing_radius, N),
                              el.bushing_radius, el.pin_radius, depth, el.law.depth)
    s = fr.joint_samples(mech, JOINT, r.ys[::8], model.force)
    inc = jax.jit(lambda c: fr.fem_increment(c, s, r.ts[::8], el.wear.coefficient))(contact)
    cold = jax.jit(jax.vmap(lambda f: contact.solve_force(f).pressure))(s.force)
    scale = float(jnp.max(cold))
    assert bool(inc.ok)
    assert float(jnp.max(jnp.abs(inc.pressure - cold))) < 1e-9 * scale

    solve = jax.jit(lambda c, f, g, w: c.solve_force(f, guess=g, window=w),
                    static_argnums=3)
    f0 = s.force[len(s.force) // 2]
    full = contact.solve_force(f0)
    narrow = solve(contact, f0, None, 4)  # 4 nodes: less than the contact arc
    assert int(jnp.sum(full.in_contact)) > 4
    assert bool(narrow.info.converged)
    assert float(jnp.max(jnp.abs(narrow.pressure - full.pressure))) < 1e-9 * scale
    again = solve(contact, f0, (full.offset, full.nodal_force), N // 2)
    assert int(again.info.steps) == 0
    assert float(jnp.max(jnp.abs(again.pressure - full.pressure))) < 1e-12 * scale

    # the closed-form depth derivative of the implicit step's J against forward
    # mode through the solve (its implicit-function step), on the window's nodes
    nodes = contact.window_nodes(f0, N // 2)
    closed = contact.force_depth_derivative(f0, full.offset, full.nodal_force, nodes)

    def nodal(extra):
        worn = eqx.tree_at(lambda c: c.boundary_radius, contact,
                           contact.boundary_radius.at[nodes].add(extra))
        return worn.solve_force(f0, guess=(full.offset, full.nodal_force)).nodal_force[nodes]

    auto = jax.jit(jax.jacfwd(nodal))(jnp.zeros(N // 2))
    assert float(jnp.max(jnp.abs(closed - auto))) < 1e-9 * float(jnp.max(jnp.abs(auto)))
    assert float(jnp.max(jnp.abs(auto))) > 0

    n = N
    l_g, f_s = (float(x) for x in contact._scales(1e-4))
    args = (contact, f0, (l_g, f_s, float(jnp.linalg.norm(f0))))
    z = jnp.concatenate([jnp.linspace(-0.3, 0.8, n), jnp.array([0.2, -0.6])])
    closed = fc._force_jacobian(z, args)
    auto = jax.jacfwd(fc._force_residual)(z, args)
    assert float(jnp.max(jnp.abs(closed - auto))) < 1e-12 * float(jnp.max(jnp.abs(auto)))


def test_bad_contact_option(tmp_path, capsys):
    """--contact takes efm or fem (argparse: exit 2 naming the option and the
    choices); the study API names the option too; fem needs method constant."""
    with pytest.raises(SystemExit) as exc:
        cli.main(["study", "rig-21400", "--contact", "bem", "--out", str(tmp_path / "x")])
    code = exc.value.code
    err = capsys.readouterr().err
    assert code == 2 and "--contact" in err and "efm" in err and "fem" in err
    with pytest.raises(InputError, match="--contact must be one of efm, fem"):
        check_contact("FEM")
    assert cli.main(["study", "ideal-slider-crank", "--contact", "fem", "--out",
                     str(tmp_path / "y")]) == 2
    assert "does not take --contact" in capsys.readouterr().err
    assert cli.main(["study", "rig-21400", "--contact", "fem", "--method", "adaptive",
                     "--cycles", "10", "--out", str(tmp_path / "z"), "--quiet"]) == 2
    assert "--method constant only" in capsys.readouterr().err
    from diffwear.cli.command import study_model
    from diffwear.models import Dynamic, FemRoute
    from diffwear.studies import STUDIES
    for name in ("rig-21400", "wear-5000"):  # both wear studies take the option
        study = STUDIES[name]
        assert type(study_model(study, 10, {})) is Dynamic  # efm by default
        assert isinstance(study_model(study, 10, {"contact": "fem"}), FemRoute)


@pytest.mark.extended
def test_the_fem_route_runs_as_its_study_beside_the_efm_route(tmp_path):
    """`diffwear study rig-21400 --contact fem` end to end (2,140 cycles, A =
    43: 50 dynamic cycles on Rodas4, the FEM route in checkpointed chunks, the
    EFM route whole beside it).  The two routes carry the same dynamics and
    the same Archard law, so their worn volumes and depths agree (measured
    +0.66 % and +0.75 %; tolerances 2 % and 5 %: at 21,400 cycles the FEM
    route's peak is ~5 % deeper); the FEM route's worn volume equals k x its
    sum of FE normal load x sliding up to the quadrature of the pressure
    (measured 1e-4; 0.9 % at 21,400 cycles; tolerance 2 %)."""
    import json

    out = tmp_path / "fem"
    assert cli.main(["study", "rig-21400", "--contact", "fem", "--cycles", "2140",
                     "--out", str(out), "--quiet"]) == 0
    s = json.loads((out / "summary.json").read_text())
    fem, efm = s["fem_route"], s["efm_route"]
    assert s["integrator"] == "rodas4" and s["contact"] == "fem"
    assert s["status"] == "ok"
    assert fem["explicit_fallback_cycles"] == 0 and fem["dynamic_cycles_simulated"] == 51
    assert fem["wear_volume_mm3"] == pytest.approx(efm["wear_volume_mm3"], rel=2e-2)
    assert fem["wear_volume_mm3"] == pytest.approx(fem["archard_k_times_load_sliding_mm3"],
                                                   rel=2e-2)
    assert fem["max_wear_depth_mm"] == pytest.approx(efm["max_wear_depth_mm"], rel=5e-2)
    assert fem["arc_peak_depth_mm"] == pytest.approx(efm["arc_peak_depth_mm"], rel=5e-2)
    assert s["max_wear_depth_mm"] == fem["max_wear_depth_mm"]
    assert "| FEM |" in (out / "report.md").read_text()
