"""What a mechanism file describes: the `Mechanism`, a coordinate guess, the
integration settings and the requested outputs."""

from __future__ import annotations

import inspect

import diffrax
import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..dynamics import Baumgarte, simulate
from ..mechanism import Mechanism

# Defaults are those of the Python API, so that a file and a script agree.
DEFAULT_ALPHA = inspect.signature(Baumgarte.__init__).parameters["alpha"].default  # 1/s
DEFAULT_BETA = inspect.signature(Baumgarte.__init__).parameters["beta"].default  # 1/s
DEFAULT_MAX_STEPS = inspect.signature(simulate).parameters["max_steps"].default
# dynamics.simulate's default controller: PID(rtol = atol = 1e-8, pcoeff 0.3,
# icoeff 0.4).  test_config's round trip checks that a file with these values
# reproduces `simulate(...)` with its defaults to 1e-12.
DEFAULT_RTOL = 1e-8
DEFAULT_ATOL = 1e-8
PID_PCOEFF = 0.3
PID_ICOEFF = 0.4
DEFAULT_N_SAVE = 401  # saved points (output resolution only, not accuracy)


class Simulation(eqx.Module):
    """``[simulation]``: integrate from t = 0 to ``duration`` [s], saving
    ``n_save`` equally spaced states; Tsit5 with a PID controller, Rodas4 for
    a mechanism with a lubricated joint
    (`diffwear.mechanism_file.motion_integrator`)."""

    duration: float = eqx.field(static=True)
    n_save: int = eqx.field(static=True, default=DEFAULT_N_SAVE)
    rtol: float = eqx.field(static=True, default=DEFAULT_RTOL)
    atol: float = eqx.field(static=True, default=DEFAULT_ATOL)
    baumgarte_alpha: float = eqx.field(static=True, default=DEFAULT_ALPHA)
    baumgarte_beta: float = eqx.field(static=True, default=DEFAULT_BETA)
    max_steps: int = eqx.field(static=True, default=DEFAULT_MAX_STEPS)

    def ts(self) -> Float[Array, " T"]:
        return jnp.linspace(0.0, self.duration, self.n_save)

    def baumgarte(self) -> Baumgarte:
        return Baumgarte(self.baumgarte_alpha, self.baumgarte_beta)

    def controller(self) -> diffrax.PIDController:
        return diffrax.PIDController(rtol=self.rtol, atol=self.atol,
                                     pcoeff=PID_PCOEFF, icoeff=PID_ICOEFF)


class ReactionOutput(eqx.Module):
    """``[outputs] reactions`` entry: the wrench ``joint`` exerts on body ``on``."""

    joint: str = eqx.field(static=True)
    on: str = eqx.field(static=True)


class ContactOutput(eqx.Module):
    """``[outputs] contact`` entry: the contact history of clearance joint ``joint``."""

    joint: str = eqx.field(static=True)


class MechanismFile(eqx.Module):
    """A loaded mechanism file (see `diffwear.config.load`).

    ``assembly``: the mechanism with every clearance joint replaced by the ideal
    revolute at the same points; the initial state is assembled on it (pin
    centred, ideal velocities).  ``None`` when there is no clearance joint.
    ``bushing_walls``: (joint name, wall thickness [m]) of the clearance joints
    that state one (the elastic foundation's layer thickness).
    """

    file: str = eqx.field(static=True)
    title: str = eqx.field(static=True)
    source: str = eqx.field(static=True)
    mechanism: Mechanism
    q_guess: Float[Array, " n"]
    simulation: Simulation
    reactions: tuple[ReactionOutput, ...] = eqx.field(static=True)
    contacts: tuple[ContactOutput, ...] = eqx.field(static=True, default=())
    assembly: Mechanism | None = None
    bushing_walls: tuple[tuple[str, float], ...] = eqx.field(static=True, default=())
