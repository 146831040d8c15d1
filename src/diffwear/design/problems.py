"""The thesis Ch. 8 design problems solved together, as the design study asks.

`solve_problems` solves equal life (always: the life maps are drawn around
its answer) and, on request, the longest common life, least material and the
robust least material (`diffwear.design.optimise`,
`diffwear.design.robust`) on a fast life model, each corrected on a
reference model by output space mapping (`space_mapped`) when the two
differ.  Least material and the robust design share one target life: the
thesis's (Table 8-5) when the model reaches it at d = 20 mm, h = 50 mm, else
the equal-life answer's.
"""

from __future__ import annotations

from collections.abc import Callable

import jax.numpy as jnp
import numpy as np

from .optimise import (
    LONGEST_LIFE_CORNER,
    AtTarget,
    DesignResult,
    equal_life,
    least_material,
    life_gap,
    life_of,
    longest_common_life,
    space_mapped,
)
from .robust import monte_carlo_check, percentile_of, robust_least_material
from .two_joint import TABLE_8_5, TwoJointLife

START = np.array([45.0e-3, 45.0e-3, 30.0e-3, 30.0e-3])  # m: the centre of the Table 8-3 box
MAX_REFERENCE_RUNS = 6  # space-mapping rounds per problem
MC_SAMPLES = 1000  # model runs of the robust design's Monte-Carlo check


def _silent(message: str) -> None:
    pass


def solve_problems(fast: TwoJointLife, reference: TwoJointLife, *,
                   with_longest_common_life: bool = False, with_least_material: bool = False,
                   with_robust: bool = False, start=START,
                   max_reference_runs: int = MAX_REFERENCE_RUNS, mc_samples: int = MC_SAMPLES,
                   log: Callable[[str], object] | None = None,
                   prefix: str = "") -> dict[str, DesignResult]:
    """The Ch. 8 design problems on ``fast``, corrected on ``reference``
    (output space mapping) unless they are the same object (module notes).

    **Arguments:**

    - ``fast``: the life model the optimisers work on (the quasi-static
      model, exact gradients).
    - ``reference``: the life model that checks and corrects each answer (the
      dynamic model), or ``fast`` itself for no correction.
    - ``with_longest_common_life``: also solve the longest common life
      (`longest_common_life`).
    - ``with_least_material``: also solve least material at the shared
      target (`least_material`).
    - ``with_robust``: also solve the robust least material at the shared
      target (`robust_least_material`; needs exact gradients of ``fast``;
      not corrected on ``reference``), with the deterministic design at the
      same target for comparison and a Monte-Carlo check of the model itself
      (`monte_carlo_check`).
    - ``start``: the equal-life problem's start (d1, d2, h1, h2) [m] (default
      the centre of the Table 8-3 box).
    - ``max_reference_runs``: space-mapping rounds per problem.
    - ``mc_samples``: sampled (k1, k2) pairs of the Monte-Carlo check.
    - ``log``: called with each progress line (None: silent).
    - ``prefix``: put before each problem's heading line.

    **Returns:** {"equal_life", and those asked of "longest_common_life",
    "least_material", "robust"}: a `DesignResult` each.  The least-material
    and robust answers name their target's source in
    ``notes["target_source"]``; the robust answer carries
    ``notes["deterministic"]`` (the least-material design at its target, with
    its percentile) and ``notes["monte_carlo_check"]`` (with ``confirms``:
    whether the reported percentile lies in the check's 95 % interval).
    `SolverError` when space mapping does not converge; `InputError` when
    least material's target is out of reach at d = 20 mm (`least_material`).
    """
    say = _silent if log is None else log
    corrected = fast is not reference

    def solve(name, problem, residual):
        say(f"{prefix}{name} ...")
        if not corrected:
            return problem(fast)
        return space_mapped(problem, fast, reference, residual,
                            max_reference_runs=max_reference_runs, log=log)

    solved = {"equal_life": solve("equal life", lambda m: equal_life(m, start), life_gap)}
    if with_longest_common_life:
        solved["longest_common_life"] = solve("longest common life", longest_common_life,
                                              life_gap)
    if with_least_material or with_robust:
        # the thesis's life if the model can reach it with d = 20 mm, else the
        # equal-life answer's (reachable: life hardly depends on d)
        corner = life_of(fast, LONGEST_LIFE_CORNER)
        target = float(TABLE_8_5["surrogate_cycles"])
        why = "thesis Table 8-5"
        if min(corner) < target:
            why = (f"the equal-life answer's life; the thesis's {target:,.0f} cycles is out of "
                   f"reach: {min(corner):,.0f} at d = 20 mm, h = 50 mm")
            target = float(np.mean(solved["equal_life"].cycles))
        if with_least_material:
            res = solve(f"least material at {target:,.0f} cycles ({why})",
                        lambda m: least_material(m, target, corner_cycles=life_of(
                            m, LONGEST_LIFE_CORNER)), AtTarget(jnp.asarray(target)))
            res.notes["target_source"] = why
            solved["least_material"] = res
        if with_robust:
            say(f"{prefix}robust least material: P10 of the weaker joint's life >= "
                f"{target:,.0f} cycles under +-50 % k scatter ...")
            res = robust_least_material(fast, target, log=log)
            res.notes["target_source"] = why
            # the deterministic least-material design at the same target, and
            # its reliability, for comparison
            nominal = least_material(fast, res.notes["target_cycles"],
                                     corner_cycles=life_of(fast, LONGEST_LIFE_CORNER))
            res.notes["deterministic"] = {
                **nominal.summary(),
                "percentile": percentile_of(nominal.cycles)["percentile"]}
            say(f"{prefix}robust: Monte-Carlo check, the model at {mc_samples} sampled k "
                "pairs ...")
            mc = monte_carlo_check(fast, res.x, n=mc_samples)
            claimed = res.notes["percentile_check"]["percentile"]
            mc["confirms"] = bool(mc["interval"][0] <= claimed <= mc["interval"][1])
            res.notes["monte_carlo_check"] = mc
            solved["robust"] = res
    return solved
