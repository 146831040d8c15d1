"""The planar rotations and the saddle-point solve, written out elementwise
for speed, against their textbook forms (a rotation matrix; the dense KKT
system solved by NumPy)."""

import os
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np

from diffwear.dynamics.equations import schur_solve
from diffwear.mechanism.frames import Frames
from diffwear.mechanism.geometry import perp

jax.config.update("jax_enable_x64", True)


def _rotation(phi):
    c, s = np.cos(phi), np.sin(phi)
    return np.array([[c, -s], [s, c]])


def test_perp_is_a_quarter_turn_on_any_batch():
    rng = np.random.default_rng(0)
    v = rng.normal(size=(5, 3, 2))
    want = v @ _rotation(np.pi / 2).T
    np.testing.assert_allclose(np.asarray(perp(jnp.asarray(v))), want, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(np.asarray(perp(jnp.array([1.0, 2.0]))), [-2.0, 1.0])


def test_frames_rotate_with_the_rotation_matrix():
    rng = np.random.default_rng(1)
    angles = np.array([0.3, -2.1, 4.0])
    q = np.column_stack([rng.normal(size=3), rng.normal(size=3), angles]).reshape(-1)
    frames = Frames({"a": 0, "b": 1, "c": 2}, jnp.ones(3), jnp.asarray(q), jnp.zeros(9))
    s = rng.normal(size=2)
    for name, phi in zip("abc", angles):
        a = _rotation(phi)
        np.testing.assert_allclose(np.asarray(frames.to_global(name, jnp.asarray(s))), a @ s,
                                   rtol=0, atol=1e-15)
        np.testing.assert_allclose(np.asarray(frames.to_body(name, jnp.asarray(s))), a.T @ s,
                                   rtol=0, atol=1e-15)
    # the ground is the fixed frame: identity rotation, zero pose and velocity,
    # and a force on it is no generalised force of the mechanism
    np.testing.assert_array_equal(np.asarray(frames.to_global("ground", jnp.asarray(s))), s)
    np.testing.assert_array_equal(np.asarray(frames.to_body("ground", jnp.asarray(s))), s)
    np.testing.assert_array_equal(np.asarray(frames.point("ground", jnp.asarray(s))), s)
    np.testing.assert_array_equal(np.asarray(frames.point_velocity("ground", jnp.asarray(s))),
                                  [0.0, 0.0])
    np.testing.assert_array_equal(np.asarray(frames.pose("ground")), [0.0, 0.0, 0.0])
    on_ground = frames.wrench("ground", jnp.array([3.0, -1.0]), at=jnp.asarray(s), torque=2.0)
    np.testing.assert_array_equal(np.asarray(on_ground), np.zeros((3, 3)))


def test_spring_to_the_ground_gives_the_hand_computed_wrench():
    """A spring from a ground point to a point of body b: tension k (L - L0)
    along the spring, on b's row only, with the moment r x F about b's COM."""
    from diffwear.mechanism import LinearSpring

    q = np.array([0.0, 0.0, 0.0, 0.4, 0.1, 0.7, 0.0, 0.0, 0.0])
    frames = Frames({"a": 0, "b": 1, "c": 2}, jnp.ones(3), jnp.asarray(q), jnp.zeros(9))
    k, free, anchor, s_b = 200.0, 0.1, np.array([-0.2, 0.3]), np.array([0.05, -0.02])
    spring = LinearSpring("s", "ground", anchor, "b", s_b, stiffness=k, free_length=free)
    got, _ = spring.forces(frames, jnp.zeros(0), 0.0)
    point = q[3:5] + _rotation(q[5]) @ s_b
    d = point - anchor
    length = np.hypot(*d)
    f_b = -k * (length - free) * d / length  # pulls b's point towards the anchor
    arm = point - q[3:5]
    want = np.zeros((3, 3))
    want[1] = [f_b[0], f_b[1], arm[0] * f_b[1] - arm[1] * f_b[0]]
    np.testing.assert_allclose(np.asarray(got), want, rtol=1e-12, atol=1e-12)


def test_schur_solve_equals_the_dense_saddle_point_solve():
    rng = np.random.default_rng(2)
    m, n = 4, 9
    jac = rng.normal(size=(m, n))
    minv = 1.0 / rng.uniform(0.5, 3.0, size=n)
    force, rhs = rng.normal(size=n), rng.normal(size=m)
    kkt = np.block([[np.diag(1.0 / minv), jac.T], [jac, np.zeros((m, m))]])
    want = np.linalg.solve(kkt, np.concatenate([force, rhs]))
    qdd, lam = schur_solve(*(jnp.asarray(x) for x in (jac, minv, force, rhs)))
    np.testing.assert_allclose(np.asarray(qdd), want[:n], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.asarray(lam), want[n:], rtol=1e-12, atol=1e-12)


def test_objects_built_on_import_keep_float64_when_x64_comes_later():
    """The ``diffwear`` command imports the package (and so builds every
    module-level object: the material and joint presets) before it switches
    on ``jax_enable_x64``; none of them may have been rounded to float32 on
    import."""
    code = (
        "import importlib, pkgutil, jax, numpy as np\n"
        "import diffwear\n"
        "modules = [importlib.import_module(m.name) for m in\n"
        "           pkgutil.walk_packages(diffwear.__path__, 'diffwear.')\n"
        "           if not m.name.endswith('__main__')]\n"
        "jax.config.update('jax_enable_x64', True)\n"
        "def leaves(obj):\n"
        "    try:\n"
        "        return jax.tree_util.tree_leaves(obj)\n"
        "    except Exception:\n"
        "        return []\n"
        "bad = sorted({f'{mod.__name__}.{name}' for mod in modules\n"
        "              for name, obj in vars(mod).items()\n"
        "              for x in leaves(obj) if isinstance(x, jax.Array)\n"
        "              and x.dtype in (np.float32, np.int32)})\n"
        "from diffwear.presets import RIG_JOINT\n"
        "print(bad)\n"
        "print(repr(float(RIG_JOINT.clearance)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=300, env={**os.environ, "JAX_ENABLE_X64": "0"})
    assert out.returncode == 0, out.stderr
    bad, clearance = out.stdout.split("\n")[:2]
    assert bad == "[]"
    assert float(clearance) == (9.533 - 9.500) * 1e-3  # Table 7-1, to the last bit
