"""Named choices of public options, in one module without heavy imports (the
command line builds its parser from them before it imports JAX)."""

from pathlib import Path

# How a wear evolution extrapolates over cycles (--method): the option's name of
# each extrapolation solver of `diffwear.wear.extrapolation`, by its class
# (the name a summary and a checkpoint record).
METHOD_OF_SOLVER = {"Constant": "constant", "Adaptive": "adaptive",
                    "ErrorControlled": "error"}
WEAR_METHODS = tuple(METHOD_OF_SOLVER.values())
# The pressure model of the wear (--contact); the dynamics always use the EFM.
WEAR_CONTACTS = ("efm", "fem")
# The wear model (--model): the dynamic reference or the quasi-static joint.
WEAR_MODELS = ("dynamic", "quasi-static")
# The forward model a calibration fits (`diffwear calibrate --model`).
CALIBRATION_MODELS = ("quasi-static", "dynamic")
# Where `diffwear sweep` runs its points (--device): auto picks the GPU when
# JAX has one; on a CPU the points run one after another (over a process per
# core when that pays), on a GPU vmapped in chunks (`diffwear.sweep.execution`).
SWEEP_DEVICES = ("auto", "cpu", "gpu")
# The dynamic cycles' integrator (--integrator; `diffwear.wear.cycle.CYCLE_INTEGRATORS`).
WEAR_INTEGRATORS = ("tsit5", "rodas4")


# Mechanism files shipped with the package, loadable by name (`diffwear run rig`).
SHIPPED_MECHANISMS = Path(__file__).resolve().parent / "config" / "mechanisms"


def shipped_mechanism_names() -> list[str]:
    return sorted(p.stem for p in SHIPPED_MECHANISMS.glob("*.toml"))

