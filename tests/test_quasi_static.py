"""The quasi-static joint model: equilibrium against closed forms and the dynamic
EFM law, the exact wear response, the wear ODE in the cycle count against
closed forms, agreement with the dynamic route (rig, Ch. 8), contact-loss
detection, and its life gradients against central differences."""

from __future__ import annotations

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from diffwear.contact import PinKinematics
from diffwear.design.two_joint import LOWER, TABLE_8_4, UPPER, TwoJointLife
from diffwear.models import QuasiStatic
from diffwear.presets import clearance_slider_crank
from diffwear.quasistatic import JointLoads, QuasiStaticJoint
from diffwear.quasistatic.joint import pin_offset
from diffwear.studies import rig_21400
from diffwear.wear import ArchardWear, arc_peak_depth, peak_depth, worn_volume
from diffwear.wear.profile_ode import integrate_profile
from diffwear.wear.status import RESULTS

# The dynamic route's results these are checked against (diffwear's own EFM
# dynamic model; README "Rig" and "Bushing design"): rig-21400 (constant
# A = 428, 51 dynamic cycles, n_theta 180): max depth 0.4449 mm at 170 deg,
# volume 106.71 mm^3.  Ch. 8 lives at the Table 8-4 design with the dynamic
# model at 40 wear steps (its lives converge as ~1/steps: 78,896 / 116,868 at
# 10 steps, 77,662 / 116,492 at 20, 77,241 / 116,310 at 40).
RIG_DYNAMIC = {"depth_mm": 0.4449, "angle_deg": 170.0, "volume_mm3": 106.71}
TABLE_8_4_DYNAMIC_40 = np.array([77_241.0, 116_310.0])


def _rig_joint():
    _, mech, y0 = rig_21400._setup()
    el = next(f for f in mech.forces if f.name == "crank_rod")
    return mech, y0, el


# ------------------------------------------------------------ equilibrium
def test_equilibrium_of_a_round_bushing_without_clearance_is_the_closed_form():
    """c = 0: the springs on the loaded half-circle carry W with e . u_k > 0,
    sum_k kk e cos^2 theta_k = kk e n / 4 = kc e, so e = W / kc exactly."""
    n, kc, w = 180, 2.5e7, 1234.5
    e, ok = pin_offset(jnp.zeros(n), jnp.array([w, 0.0]), kc, 1e-12)
    assert float(ok) == 1.0
    np.testing.assert_allclose(np.asarray(e), [w / kc, 0.0], rtol=1e-10, atol=1e-18)
    # any direction: the same magnitude along the load
    ang = 0.3
    e2, _ = pin_offset(jnp.zeros(n), w * jnp.array([math.cos(ang), math.sin(ang)]), kc, 1e-12)
    np.testing.assert_allclose(float(jnp.linalg.norm(e2)), w / kc, rtol=2e-3)


def test_equilibrium_balances_the_dynamic_efm_law_with_friction():
    """At the quasi-static offset (pin at rest relative to the bushing, turning
    at omega) the dynamic EFM law's own force on the pin is minus the load,
    friction included: the friction reduction W' = (I + f P)^-1 W is exact."""
    mech, y0, el = _rig_joint()
    j = QuasiStaticJoint.from_joint(el)
    n = j.n
    theta = 2 * np.pi * np.arange(n) / n
    depth = jnp.asarray(0.2e-3 * np.exp(-((theta - 2.9) / 0.4) ** 2))  # a worn groove
    rng = np.random.default_rng(0)
    for _ in range(5):
        w = jnp.asarray(rng.normal(size=2) * 150.0)
        omega = jnp.asarray(rng.choice([-1, 1]) * rng.uniform(0.5, 4.0))
        loads = JointLoads(force=w[None, :], omega=omega[None], period=jnp.asarray(2.0))
        eq = j.equilibrium(depth, loads)
        assert bool(eq.ok)
        kin = PinKinematics(offset=eq.offset[0], offset_rate=jnp.zeros(2), omega=omega,
                            pin_radius=j.pin_radius, bushing_radius=j.bushing_radius)
        res = el.law.evaluate(kin, jnp.zeros(0), el.profile.worn(depth), el.friction)
        np.testing.assert_allclose(np.asarray(res.force), -np.asarray(w), rtol=1e-8,
                                   atol=1e-8 * float(jnp.linalg.norm(w)))
        np.testing.assert_allclose(float(res.normal_load), float(eq.normal_load[0]), rtol=1e-10)


def test_wear_response_is_the_exact_jacobian_of_the_cycle_wear():
    mech, y0, el = _rig_joint()
    qs = QuasiStatic(samples=90)
    loads = qs.loads(mech, ("crank_rod",), y0, 2.0).joints[0]
    j = QuasiStaticJoint.from_joint(el)
    h = jnp.zeros(j.n)
    for _ in range(3):  # a worn profile
        dh, _, _ = j.cycle_wear(h, loads)
        h = h + 1500.0 * dh
    a = j.wear_response(h, loads)
    jac = jax.jacfwd(lambda h: j.cycle_wear(h, loads)[0])(h)
    np.testing.assert_allclose(np.asarray(a), -np.asarray(jac), rtol=0,
                               atol=1e-9 * float(jnp.max(jnp.abs(jac))))
    np.testing.assert_allclose(np.asarray(a), np.asarray(a).T, atol=1e-12 * float(jnp.max(a)))


# ------------------------------------------------------------ wear ODE and peak
def test_peak_depth_of_a_smooth_bump_between_nodes():
    n = 90
    theta = 2 * np.pi * np.arange(n) / n
    for centre in (1.0, 1.0 + 0.5 * 2 * np.pi / n, 4.3):
        h = jnp.asarray(1e-3 * np.exp(-((theta - centre) / 0.3) ** 2))
        p = float(peak_depth(h))
        assert p >= float(jnp.max(h))
        # within 1e-3 of the true peak (the grid maximum misses it by up to 1.4 %)
        np.testing.assert_allclose(p, 1e-3, rtol=1e-3)
    assert float(peak_depth(jnp.full(n, 2e-4))) == pytest.approx(2e-4, rel=1e-14)


def test_arc_peak_depth_is_the_dirichlet_mean_of_a_cosine_groove():
    """The +-4 deg mean of h = h0 (1 + cos(theta - phi)) on 180 nodes (2 nodes
    each side) peaks at the node nearest phi; on a node its value is the
    Dirichlet kernel h0 (1 + sin(5 d / 2) / (5 sin(d / 2))), d = 2 deg.  A
    node-to-node zigzag of +-e on the groove averages to within e / 5 of the
    smooth groove's value; a constant profile and a zero half-width give the
    grid maximum."""
    n, h0 = 180, 2e-4
    d = 2 * math.pi / n
    theta = d * np.arange(n)
    h = h0 * (1.0 + np.cos(theta - 37 * d))
    want = h0 * (1.0 + math.sin(2.5 * d) / (5.0 * math.sin(0.5 * d)))
    assert float(arc_peak_depth(jnp.asarray(h))) == pytest.approx(want, rel=1e-13)
    zigzag = h + 1e-5 * (-1.0) ** np.arange(n)
    assert float(np.max(zigzag)) - want > 0.9e-5  # the grid maximum carries it whole
    assert abs(float(arc_peak_depth(jnp.asarray(zigzag))) - want) <= 1e-5 / 5 + 1e-18
    assert float(arc_peak_depth(jnp.full(n, h0))) == pytest.approx(h0, rel=1e-14)
    assert float(arc_peak_depth(jnp.asarray(zigzag), half_width=0.0)) == float(np.max(zigzag))


def test_peak_depth_derivative_is_continuous_as_the_peak_crosses_a_node():
    """d peak / d centre of a bump moving across node 30: no jump (the grid
    maximum's derivative would jump from one node's weight to the next)."""
    n = 90
    theta = jnp.asarray(2 * np.pi * np.arange(n) / n)

    def peak_at(c):
        return peak_depth(jnp.exp(-((theta - c) / 0.3) ** 2))

    node = float(theta[30])
    eps = 1e-7
    left = jax.grad(peak_at)(node - eps)
    right = jax.grad(peak_at)(node + eps)
    assert abs(float(left) - float(right)) < 1e-4
    assert abs(float(left)) < 2e-3  # the true peak height does not depend on the centre


def test_constant_wear_rate_gives_the_closed_form_life_and_profile():
    """w(h) = b (no response): h(N) = N b, life = limit / peak(b) exactly."""
    n = 60
    theta = 2 * np.pi * np.arange(n) / n
    b = jnp.asarray(3e-8 * (1.2 + np.cos(theta - 0.7)))

    def evaluate(h):
        return b, jnp.asarray(True), jnp.zeros((n, n))

    sol = integrate_profile(evaluate, jnp.zeros(n), steps=7, limit=2e-3)
    assert bool(sol.result == RESULTS.ok)
    np.testing.assert_allclose(float(sol.life[0]), 2e-3 / float(peak_depth(b)), rtol=1e-10)
    run = integrate_profile(evaluate, jnp.zeros(n), steps=5, cycles=12_345.0)
    np.testing.assert_allclose(np.asarray(run.depth[0]), 12_345.0 * np.asarray(b), rtol=1e-12)
    np.testing.assert_allclose(float(run.cycles), 12_345.0, rtol=1e-14)


def test_a_run_through_the_wall_stops_at_the_wall():
    """w = b constant: the wall is reached at wall / peak(b) cycles exactly,
    however long the requested run; the profile there is that many cycles of
    b (not the overshoot of a long step); with a response A the stop lands on
    the wall depth and the same cycles as a life to it."""
    n = 60
    theta = 2 * np.pi * np.arange(n) / n
    b = jnp.asarray(3e-8 * (1.2 + np.cos(theta - 0.7)))

    def evaluate(h):
        return b, jnp.asarray(True), jnp.zeros((n, n))

    wall = 5e-3
    run = integrate_profile(evaluate, jnp.zeros(n), steps=5, cycles=1e12, wall=wall)
    assert bool(run.result == RESULTS.wall_reached)
    reached = wall / float(peak_depth(b))
    np.testing.assert_allclose(float(run.cycles), reached, rtol=1e-10)
    np.testing.assert_allclose(np.asarray(run.depth[0]), reached * np.asarray(b), rtol=1e-9)

    a = 2e-6 * jnp.eye(n) + 1e-7

    def responding(h):
        return b - a @ h, jnp.asarray(True), a

    run = integrate_profile(responding, jnp.zeros(n), steps=40, cycles=1e12, wall=wall)
    life = integrate_profile(responding, jnp.zeros(n), steps=40, limit=wall)
    assert bool(run.result == RESULTS.wall_reached)
    np.testing.assert_allclose(float(peak_depth(run.depth[0])), wall, rtol=1e-9)
    np.testing.assert_allclose(float(run.cycles), float(life.life[0]), rtol=1e-3)


def test_linear_wear_ode_converges_to_its_exact_solution():
    """dh/dN = b - A h (A symmetric positive definite): h(N) = A^-1 (I - e^{-AN}) b."""
    n = 12
    rng = np.random.default_rng(3)
    q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    lam = np.geomspace(1e-6, 5e-3, n)
    a = (q * lam) @ q.T
    b = 1e-7 * rng.uniform(0.5, 1.5, n)
    cycles = 20_000.0
    exact = q @ (((1 - np.exp(-lam * cycles)) / lam) * (q.T @ b))

    def evaluate(h):
        return jnp.asarray(b) - jnp.asarray(a) @ h, jnp.asarray(True), jnp.asarray(a)

    errors = []
    for steps in (10, 40):
        run = integrate_profile(evaluate, jnp.zeros(n), steps=steps, cycles=cycles,
                                max_steps=steps + 2)
        errors.append(np.max(np.abs(np.asarray(run.depth[0]) - exact)) / np.max(np.abs(exact)))
    assert errors[1] < 2e-2 and errors[1] < 0.5 * errors[0]


# ------------------------------------------------------------ against the dynamic route
def test_rig_21400_agrees_with_the_dynamic_route():
    mech, y0, el = _rig_joint()
    run = eqx.filter_jit(lambda m: QuasiStatic().evolve(m, ("crank_rod",), y0, period=2.0,
                                                        cycles=21_400.0))(mech)
    assert bool(run.result == RESULTS.ok)
    h = np.asarray(run.depth[0])
    depth = h.max() * 1e3
    volume = float(worn_volume(h, el.bushing_radius, el.law.depth)) * 1e9
    assert depth == pytest.approx(RIG_DYNAMIC["depth_mm"], rel=1e-2)
    assert volume == pytest.approx(RIG_DYNAMIC["volume_mm3"], rel=1e-2)
    assert abs(np.argmax(h) * 360.0 / h.size - RIG_DYNAMIC["angle_deg"]) <= 4.0
    assert float(run.contact_margin[0]) > 1.0


def test_table_8_4_lives_agree_with_the_dynamic_model():
    model = TwoJointLife().prepared()
    cycles = model.life(TABLE_8_4)
    np.testing.assert_allclose(cycles, TABLE_8_4_DYNAMIC_40, rtol=1e-2)


def test_life_scales_as_one_over_the_wear_coefficient():
    """Archard's rate is linear in k and the equilibrium does not depend on it,
    so the life is exactly proportional to 1 / k (the robust design relies on it)."""
    model = TwoJointLife(wear_model=QuasiStatic(steps=10, samples=60), n_theta=36).prepared()
    x = jnp.asarray(TABLE_8_4)
    f = eqx.filter_jit(lambda s: model.evaluate(x, s).life)
    base = np.asarray(f(jnp.ones(2)))
    scaled = np.asarray(f(jnp.array([0.6, 1.7])))
    np.testing.assert_allclose(scaled * np.array([0.6, 1.7]), base, rtol=1e-9)


# ------------------------------------------------------------ validity
@pytest.mark.parametrize("clearance, lost", [(0.5e-3, False), (5e-3, True)])
def test_contact_loss_is_detected(clearance, lost):
    """Table 2-1 slider-crank: at 5 mm the load turns faster than it can hold
    the pin on the wall (thesis Fig. 3-7: contact briefly lost); at 0.5 mm not."""
    mech, y0 = clearance_slider_crank("efm", clearance, wear=ArchardWear(5.05e-13), n_theta=72)
    run = eqx.filter_jit(lambda m: QuasiStatic(samples=90, steps=5).evolve(
        m, ("crank_rod",), y0, period=2.0, cycles=100.0))(mech)
    assert bool(run.result == RESULTS.contact_lost) == lost
    assert (float(run.contact_margin[0]) < 1.0) == lost


# ------------------------------------------------------------ gradients
def _designs(count: int) -> np.ndarray:
    """``count`` designs spread over the Table 8-3 box: its 16 corners pulled
    1 % inside (edges), the centre, and scrambled interior points."""
    corners = np.array([[LOWER[i] if (k >> i) & 1 == 0 else UPPER[i] for i in range(4)]
                        for k in range(16)])
    span = UPPER - LOWER
    corners = np.clip(corners, LOWER + 0.01 * span, UPPER - 0.01 * span)
    rng = np.random.default_rng(7)
    inner = LOWER + span * rng.uniform(0.1, 0.9, (count - 17, 4))
    return np.concatenate([corners, 0.5 * (LOWER + UPPER)[None], inner])


@pytest.mark.extended
def test_life_jacobian_matches_central_differences_at_the_2mm_limit():
    """jax.jacfwd of (cyc1, cyc2) w.r.t. (d1, d2, h1, h2) against central
    differences of the same model (relative step 1e-4) within 1e-4 of each
    row's largest entry at 20 designs (box corners, centre, interior), and
    reverse mode (jax.jacrev) against jax.jacfwd within 1e-8.  Coarse settings
    (the derivative is that of the discrete model, whatever its resolution)."""
    model = TwoJointLife(wear_model=QuasiStatic(steps=10, samples=60), n_theta=36).prepared()
    xs = jnp.asarray(_designs(20))
    life = jax.jit(jax.vmap(model))
    jac = np.asarray(jax.jit(jax.vmap(jax.jacfwd(model)))(xs))
    step = 1e-4 * np.asarray(xs)
    eye = np.eye(4)
    plus = np.asarray(life(jnp.asarray((np.asarray(xs)[:, None, :] + step[:, :, None] * eye)
                                       .reshape(-1, 4)))).reshape(20, 4, 2)
    minus = np.asarray(life(jnp.asarray((np.asarray(xs)[:, None, :] - step[:, :, None] * eye)
                                        .reshape(-1, 4)))).reshape(20, 4, 2)
    fd = np.swapaxes((plus - minus) / (2 * step[:, :, None]), 1, 2)  # (design, life, variable)
    scale = np.abs(fd).max(axis=2, keepdims=True)
    err = np.abs(jac - fd) / scale
    assert np.all(np.isfinite(jac))
    assert err.max() < 1e-4, err.max(axis=2)
    # reverse mode one design at a time: on XLA's CPU runtime (jaxlib 0.10.2)
    # the vmapped reverse-mode program of this life can stall with every
    # worker thread idle (docs/notes/cpu-sweeps.md)
    rev = jax.jit(jax.jacrev(model))
    grads = np.stack([np.asarray(rev(x)) for x in xs])
    np.testing.assert_allclose(grads, jac, rtol=0, atol=1e-8 * np.abs(jac).max())
    # life rises with the joint's own depth everywhere in the box
    assert np.all(jac[:, 0, 2] > 0) and np.all(jac[:, 1, 3] > 0)


# ------------------------------------------------------------ the wear studies
def test_wear_study_on_the_quasi_static_model(tmp_path):
    """``diffwear study wear-5000 --model quasi-static``: every output, and the
    same numbers as the model called directly."""
    import json

    from diffwear.cli import main

    out = tmp_path / "w"
    assert main(["study", "wear-5000", "--model", "quasi-static", "--cycles", "500", "--quiet",
                 "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["model"] == "quasi-static" and s["cycles"] == 500
    assert s["status"] == "ok"
    profile = np.loadtxt(out / "wear_profile.csv", delimiter=",", skiprows=1)
    assert s["max_wear_depth_mm"] == pytest.approx(profile[:, 1].max(), rel=1e-9)
    history = np.loadtxt(out / "wear_history.csv", delimiter=",", skiprows=1)
    assert history[0, 0] == 0 and history[-1, 0] == pytest.approx(500)
    assert history[-1, 2] == pytest.approx(s["wear_volume_mm3"], rel=1e-9)
    for name in ("report.md", "wear_profile.png", "wear_history.png",
                 "contact_locus_and_force.png", "joint_force_last_cycle.csv"):
        assert (out / name).stat().st_size > 0
    # 500 cycles are not the thesis's 5,000: its values are not put beside them
    report = (out / "report.md").read_text()
    assert s["thesis"] == {} and "5,000 cycles and this run has 500" in s["thesis_not_compared"]
    assert "not compared" in report and "Table 6-4" not in report.split("\n| quantity")[1]
    # one run time, one compile time; the contact margin and the unchanged
    # joint force explained (the force is the ideal mechanism's in every cycle)
    assert report.count("run time") == 1 and report.count("compile time") == 1
    assert "wall time" not in report and "the load holds the pin on the wall" in report
    first = np.loadtxt(out / "joint_force_first_cycle.csv", delimiter=",", skiprows=1)
    last = np.loadtxt(out / "joint_force_last_cycle.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(first[:, 1:4], last[:, 1:4])
    assert "which the wear does not change" in report


@pytest.mark.parametrize("extra, word", [(["--method", "adaptive"], "--method"),
                                          (["--contact", "fem"], "--contact")])
def test_wear_study_options_of_the_dynamic_model_are_refused(tmp_path, capsys, extra, word):
    from diffwear.cli import main

    out = tmp_path / "w"
    assert main(["study", "wear-5000", "--model", "quasi-static", *extra, "--out",
                 str(out)]) == 2
    assert word in capsys.readouterr().err


# ------------------------------------------------------------ sweep model
@pytest.mark.extended
def test_rig_wear_sweep_model_on_the_quasi_static_model():
    """`RigWear(wear_model=QuasiStatic())`: the rig's depth and volume as in the
    study, and exact gradients w.r.t. all six swept parameters (k, clearance,
    bushing depth, pin diameter, mu, spring free length) and the rod's length
    and mass: jax.jacfwd against central differences (`gradcheck`, relative
    steps 1e-3 and 1e-4, 1e-4 of each row's largest entry)."""
    from diffwear import gradcheck
    from diffwear.sweep.models import RigWear

    model = RigWear(wear_model=QuasiStatic(samples=90, steps=10), n_theta=72)
    base = model.defaults
    names = list(model.param_names)

    def outputs(x):
        params = {n: base[n] * (1.0 + x[i]) for i, n in enumerate(names)}
        m = eqx.tree_at(lambda r: (r.p.l2, r.p.m2), model,
                        (model.p.l2 * (1.0 + x[-2]), model.p.m2 * (1.0 + x[-1])))
        out = m(params)
        return jnp.stack([out["max_depth_mm"], out["volume_mm3"], out["mean_joint_force_N"]])

    x0 = jnp.zeros(len(names) + 2)
    check = gradcheck(outputs, x0, steps=(1e-3, 1e-4))
    assert check.value[0] == pytest.approx(RIG_DYNAMIC["depth_mm"], rel=2e-2)
    assert check.value[1] == pytest.approx(RIG_DYNAMIC["volume_mm3"], rel=2e-2)
    assert check.ok, check.message
    jac = check.autodiff
    assert np.all(jac[:2, 0] > 0) and np.all(jac[2, :5] == 0)  # wear grows with k; the
    # ideal mechanism's force does not see the bushing
