"""The benchmark cases, one module per case family, and their registry
`CASES`: name -> function(repeats) -> metrics, in the order the harness runs
and lists them."""

from __future__ import annotations

from collections.abc import Callable

from .calibration import CALIBRATION_DATASETS, calibration_loop
from .cycle_profile import rig_profile
from .design import ch8_optimisation, quasi_static_life_gradient, quasi_static_life_sweep
from .dynamic import clearance_cycle, ideal_slider_crank, rig_21400, rig_cycle_integrators
from .fem import rig_21400_fem_route
from .gradients import rig_cycle_gradient, rig_gradient
from .peers import exudyn_peer, scipy_peer
from .quasi_static import file_runs, rig_21400_quasi_static, rig_lubricated_quasi_static
from .sweeps import cpu_sweep, vmap_sweep

CASES: dict[str, Callable[[int], dict]] = {
    "ideal slider-crank, 2 s": ideal_slider_crank,
    **{f"clearance cycle, {law.upper()} c={c:g} mm": clearance_cycle(law, c)
       for law in ("ln", "kv", "efm") for c in (0.0005, 0.05, 0.5, 5.0)},
    "rig-21400 (constant A)": rig_21400,
    "rig-21400 FEM vs EFM route": rig_21400_fem_route,
    "vmap sweep 64 points vs 64 single runs": vmap_sweep,
    "rig cycle, Tsit5 and Rodas4": rig_cycle_integrators,
    "rig-21400 (Rodas4)": lambda r: rig_21400(r, "rodas4"),
    "rig-21400 gradient (4 parameters)": rig_gradient,
    "rig-21400 gradient (4 parameters, Rodas4)": lambda r: rig_gradient(r, "rodas4"),
    "rig-21400 gradient (4 parameters, Rodas4 at rtol 1e-6)":
        lambda r: rig_gradient(r, "rodas4", 1e-6),
    "rig cycle gradient (4 parameters, settled, Rodas4 at rtol 1e-6)": rig_cycle_gradient,
    "rig cycle profile": rig_profile,
    "ch8-optimisation": ch8_optimisation,
    "rig-21400 quasi-static": rig_21400_quasi_static,
    "rig-lubricated quasi-static (beside the dry rig)": rig_lubricated_quasi_static,
    "four-bar files, diffwear run end to end (lubricated beside dry)": file_runs,
    "quasi-static life gradient (4 parameters)": quasi_static_life_gradient,
    "quasi-static life sweep, 1000 designs": quasi_static_life_sweep,
    "CPU sweep, quasi-static rig, 64 points (batched, looped, pooled, default vs loop)":
        cpu_sweep("quasi-static"),
    "CPU sweep, dynamic rig, 8 points (batched, looped, pooled, default vs loop)":
        cpu_sweep("dynamic"),
    "calibration loop": calibration_loop,
    "calibration loop, discrepancy search (three-lobed k)":
        lambda r: calibration_loop(r, CALIBRATION_DATASETS / "campaign_three_lobe_k"),
    "calibration loop, two effects (run-in and creep)":
        lambda r: calibration_loop(r, CALIBRATION_DATASETS / "campaign_run_in_and_creep"),
    "scipy-peer": scipy_peer,
    "exudyn-peer": exudyn_peer,
}
