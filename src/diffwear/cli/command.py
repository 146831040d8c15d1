"""The ``diffwear`` command line.

Exit codes: 0 success, 2 bad input (`InputError`, unknown study, bad option),
3 solver failure (`SolverError`), 4 results not written (`OutputError`: a full
disk), 130 interrupted (Ctrl-C).
"""

from __future__ import annotations

import argparse
import atexit
import errno
import inspect
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from .._checks import check_int_option
from ..choices import (
    CALIBRATION_MODELS,
    SWEEP_DEVICES,
    WEAR_CONTACTS,
    WEAR_INTEGRATORS,
    WEAR_METHODS,
    WEAR_MODELS,
    shipped_mechanism_names,
)
from ..errors import DiffwearError, InputError

# a write that failed for want of room or of a writable disk
_DISK_ERRNOS = {errno.ENOSPC, errno.EFBIG, errno.EROFS, errno.EIO,
                getattr(errno, "EDQUOT", errno.ENOSPC)}

# Upper bound of --cycles: 1e8 crank cycles is ~6 years at 30 rpm.
MAX_CYCLES = 100_000_000


def _log(args: argparse.Namespace):
    """Where a driver's progress lines go: ``print``, or nowhere with --quiet."""
    return (lambda *a, **k: None) if args.quiet else print


def _study(args: argparse.Namespace) -> int:
    from ..io import OutputDir
    from ..studies import STUDIES

    if args.list or args.name is None:
        if args.out is not None and not args.list:
            raise InputError(f"study: name the study to run (available: {', '.join(STUDIES)}); "
                             f"nothing was written to {args.out}")
        width = max(len(n) for n in STUDIES)
        for name, module in STUDIES.items():
            print(f"{name:<{width}}  {module.DESCRIPTION}")
        return 0
    if args.name not in STUDIES:
        raise InputError(f"unknown study {args.name!r}; available: {', '.join(STUDIES)}")
    _resume_folder(args)
    if args.out is None:
        raise InputError("study: --out DIR is required")
    kwargs = {}
    accepted = inspect.signature(STUDIES[args.name].run).parameters
    if args.resume is not None and "resume" not in accepted:
        raise InputError(f"study {args.name!r} does not take --resume (wear studies do)")
    _options_from_checkpoint(args)
    if args.cycles is not None:
        check_int_option("--cycles", args.cycles, 1, MAX_CYCLES)
    chosen = {option: getattr(args, option) for option in ("method", "contact", "model",
                                                            "integrator")
              if getattr(args, option) is not None}
    # --method, --contact, --model and --integrator choose a wear study's model
    for option in ("cycles", *chosen):
        if option not in accepted and (option == "cycles" or "model" not in accepted):
            if getattr(args, option) is not None:
                raise InputError(f"study {args.name!r} does not take --{option}")
    if args.cycles is not None:
        kwargs["cycles"] = args.cycles
    if "model" in accepted:
        cycles = accepted["cycles"].default if args.cycles is None else args.cycles
        kwargs["model"] = study_model(STUDIES[args.name], cycles, chosen,
                                      resume=args.resume is not None)
    if args.resume is not None:
        kwargs["resume"] = True
    if "progress" in accepted:
        kwargs["progress"] = not args.quiet
    out = OutputDir(args.out, overwrite=args.overwrite,  # after every input check
                    resume=args.resume is not None)
    log = _log(args)
    STUDIES[args.name].run(out, log=log, **kwargs)
    return 0


def study_model(study, cycles, chosen: dict, *, resume: bool = False):
    """The wear model of a wear study from ``--model``, ``--method``,
    ``--contact`` and ``--integrator`` (the study's defaults where not given:
    the dynamic model with the EFM pressure on the study's integrator)."""
    from ..wear.fem_route import default_model
    from . import objects

    model, method = chosen.get("model", "dynamic"), chosen.get("method", "constant")
    contact = objects.check_contact(chosen.get("contact", "efm"))
    objects.check_wear_model(model, ((method != "constant", f"--method {method}"),
                                     (contact != "efm", f"--contact {contact}"),
                                     ("integrator" in chosen,
                                      f"--integrator {chosen.get('integrator')}"),
                                     (resume, "--resume")))
    integrator = chosen.get("integrator", study.INTEGRATOR)
    fem = default_model(study.DESIGN) if contact == "fem" else None
    if fem is not None and method != "constant":
        raise InputError(f"--contact fem runs with --method constant only (constant A, as "
                         f"the thesis's FEM route), got --method {method}")
    return objects.wear_model(model, cycles=cycles, method=method,
                              target_dynamic=study.TARGET_DYNAMIC, integrator=integrator,
                              fem=fem)


def _resume_folder(args: argparse.Namespace) -> None:
    """--resume DIR writes into DIR: --out is DIR or left out."""
    if args.resume is None:
        return
    if args.out is not None and Path(args.out).resolve() != Path(args.resume).resolve():
        raise InputError(f"--resume {args.resume} writes its results there; --out "
                         f"{args.out} must be the same folder or left out")
    args.out = args.resume


# options a wear study's checkpoint records (meta key -> argument), read back
# by --resume so that the user need not repeat them
_RESUMED_OPTIONS = {"cycles": "cycles", "method": "method", "contact": "contact",
                    "model": "model", "limit_mm": "limit", "integrator": "integrator"}


def _options_from_checkpoint(args: argparse.Namespace, origin: str = "") -> None:
    """--resume DIR: `InputError` unless DIR holds a checkpoint (``origin``
    says which runs write one); fill the options the user left out from its
    record (an option given explicitly is kept: the study then checks it
    matches)."""
    from ..io import CHECKPOINT
    from ..models.execution import load_checkpoint

    if args.resume is None:
        return
    path = Path(args.resume) / CHECKPOINT
    if not path.is_file():
        raise InputError(f"--resume {args.resume}: no {CHECKPOINT} there to resume from{origin}")
    from ..models.execution import META_DEFAULTS

    _, meta = load_checkpoint(path)
    # a key added later: what the checkpoints written without it meant
    meta = {**{k: v for k, v in META_DEFAULTS.items() if hasattr(args, _RESUMED_OPTIONS[k])},
            **meta}
    for key, option in _RESUMED_OPTIONS.items():
        if getattr(args, option, None) is None and key in meta:
            value = meta[key]
            setattr(args, option, int(value) if key == "cycles" else value)


# The lines of a Ctrl-C with nothing to resume (the launcher, which runs
# before the package is imported, prints the first as well).
INTERRUPTED = "diffwear: interrupted; no results were written"
INTERRUPTED_AT_THE_END = "diffwear: interrupted as the run ended; its results were written"


def _interrupted(args: argparse.Namespace, folders) -> str:
    """One line for Ctrl-C: where the checkpoint is and how to resume."""
    from ..io import CHECKPOINT

    for out in folders:
        if (out.path / CHECKPOINT).is_file() and not (out.path / "summary.json").exists():
            name, file = getattr(args, "name", None), getattr(args, "file", None)
            command = (f"diffwear study {name} --resume {out.path}" if name else
                       f"diffwear run {file} --resume {out.path}" if file else
                       f"--resume {out.path}")
            return (f"diffwear: interrupted; the checkpoint {out.path / CHECKPOINT} holds the "
                    f"run so far: resume with `{command}`")
    return INTERRUPTED


def _run(args: argparse.Namespace) -> int:
    from ..config import load
    from ..config.loader import decode
    from . import run as runner

    mfile = load(args.file)  # every input check happens before --out is touched
    text = decode(Path(mfile.file).read_bytes(), mfile.file)
    _resume_folder(args)
    if args.out is None:
        raise InputError("run: --out DIR is required")
    _options_from_checkpoint(args, " (checkpoints come from a --model dynamic wear run)")
    if args.cycles is not None:
        check_int_option("--cycles", args.cycles, 1, MAX_CYCLES)
    limit = None
    if args.limit is not None:
        if args.cycles is None:
            raise InputError("--limit MM needs --cycles N (the wear study it ends)")
        if not (0.0 < args.limit < 1e3):
            raise InputError(f"--limit {args.limit:g}: a wear depth in mm; allowed: (0, 1000)")
        limit = args.limit * 1e-3
    log = _log(args)
    runner.run(mfile, args.out, overwrite=args.overwrite, input_text=text, log=log,
               cycles=args.cycles, limit=limit, model=args.model or "quasi-static",
               method=args.method or "constant", resume=args.resume is not None,
               progress=not args.quiet, yes=args.yes)
    return 0


def _sweep(args: argparse.Namespace) -> int:
    from ..config.loader import decode
    from ..config.sweep import MAX_POINTS, load_sweep
    from ..io import OutputDir
    from . import sweep as driver

    spec = load_sweep(args.file)  # every input check happens before --out is touched
    if args.chunk_size is not None:
        check_int_option("--chunk-size", args.chunk_size, 1, MAX_POINTS)
    if args.workers is not None:
        check_int_option("--workers", args.workers, 1, 1024)
    if args.device != "auto" and (args.workers is not None or args.cluster is not None):
        raise InputError(f"--device {args.device} belongs to a sweep on this machine; with "
                         "--cluster or --workers each Dask worker runs its points itself")
    if args.workers is not None and args.cluster is not None:
        raise InputError("--cluster ADDRESS and --workers N exclude each other (--workers "
                         "starts a local cluster)")
    if args.cluster is None and args.workers is None:
        driver.device_platform(args.device)  # a GPU asked for and missing: before --out
    text = decode(Path(args.file).read_bytes(), args.file)
    log = _log(args)
    out = OutputDir(args.out, overwrite=args.overwrite)
    if args.cluster is None and args.workers is None:
        driver.run(spec, out, chunk_size=args.chunk_size, input_text=text, log=log,
                   device=args.device, progress=not args.quiet)
        return 0
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError(
            "--cluster / --workers need Dask: pip install 'diffwear[cluster]'") from None
    if args.cluster is not None:
        try:
            client = Client(args.cluster, timeout="20s")
        except (OSError, TimeoutError) as err:
            raise InputError(f"--cluster {args.cluster}: cannot connect ({err})") from None
        with client:
            driver.run(spec, out, chunk_size=args.chunk_size, client=client, input_text=text,
                      log=log)
        return 0
    with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        driver.run(spec, out, chunk_size=args.chunk_size, client=client, input_text=text, log=log)
    return 0


def _design(args: argparse.Namespace) -> int:
    from ..io import OutputDir
    from . import design as driver

    if args.list or args.name is None:
        if args.out is not None and not args.list:
            raise InputError(f"design: name the problem to solve (available: {driver.NAME}); "
                             f"nothing was written to {args.out}")
        print(f"{driver.NAME}  {driver.DESCRIPTION}")
        return 0
    if args.name != driver.NAME:
        raise InputError(f"unknown design problem {args.name!r}; available: {driver.NAME}")
    if args.out is None:
        raise InputError("design: --out DIR is required")
    settings = driver.settings(quick=args.quick, steps=args.steps,
                              dynamic_steps=args.dynamic_steps, map_points=args.map_points,
                              n_theta=args.n_theta, problems=args.problems, model=args.model)
    out = OutputDir(args.out, overwrite=args.overwrite)  # after every input check
    log = _log(args)
    driver.run(out, settings=settings, log=log)
    return 0


def _life(args: argparse.Namespace) -> int:
    from ..io import OutputDir
    from . import life as driver

    if args.name != driver.NAME:
        raise InputError(f"unknown life problem {args.name!r}; available: {driver.NAME}")
    if args.out is None:
        raise InputError("life: --out DIR is required")
    x = driver.design_from_mm((args.d1, args.d2, args.h1, args.h2))
    if args.model not in driver.MODELS:
        raise InputError(f"--model: unknown model {args.model!r}; choose from "
                         f"{', '.join(driver.MODELS)}")
    out = OutputDir(args.out, overwrite=args.overwrite)  # after every input check
    log = _log(args)
    driver.run(out, x, model=args.model, with_jacobian=args.jacobian, log=log)
    return 0


def _calibrate(args: argparse.Namespace) -> int:
    from ..calibrate import load_dataset
    from ..calibrate.fit import ModelSettings, Problem
    from ..calibrate.forecast import Outlook
    from ..calibrate.identify import discrepancy_variables, require_fit_points
    from ..calibrate.posterior import require_sampling
    from ..io import OutputDir
    from . import objects
    from .calibrate import run

    data = load_dataset(args.data)  # every input check happens before --out is touched
    require_fit_points(data)
    variables = discrepancy_variables(data, args.discrepancy)
    check_int_option("--top", args.top, 1, 5)
    if args.dynamic_cycles is not None:
        check_int_option("--dynamic-cycles", args.dynamic_cycles, 1, 2000)
    check_int_option("--n-theta", args.n_theta, 12, 720)
    settings = ModelSettings(model=objects.calibration_model(args.model),
                             dynamic_cycles=args.dynamic_cycles, n_theta=args.n_theta)
    # the models' own limits (the dynamic check's too), before --out is touched
    settings.build(data.max_cycles)
    if settings.model.checked_on_dynamic and not args.no_dynamic_check:
        settings.with_model(objects.calibration_model("dynamic")).build(data.max_cycles)
    outlook = Outlook(method=args.posterior,
                      limit=None if args.limit is None else args.limit * 1e-3,
                      horizon=args.horizon)
    # a bad limit or horizon, or a sampler the data cannot feed, before --out is touched
    problem = Problem.from_dataset(data, settings)
    outlook.resolved(data, problem)
    if args.posterior == "nuts":
        require_sampling(data, problem)
    out = OutputDir(args.out, overwrite=args.overwrite)
    log = _log(args)
    run(data, out, settings=settings, top=args.top, check=not args.no_dynamic_check,
        discrepancy=variables, outlook=outlook, log=log)
    return 0


EXIT_CODES = "Exit codes: 0 success, 2 bad input, 3 solver failure."


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("diffwear")
    except PackageNotFoundError:  # a source tree without metadata
        return "unknown"


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        # every command's --help ends with the exit codes
        kwargs.setdefault("epilog", EXIT_CODES)
        super().__init__(*args, **kwargs)

    def error(self, message):  # argparse exits with 2 already; keep its message
        self.print_usage(sys.stderr)
        self.exit(2, f"{self.prog}: error: {message}\n")


def _output_options(p: argparse.ArgumentParser, *, required: bool) -> None:
    """--out and --overwrite, shared by every command that writes results."""
    p.add_argument("--out", required=required,
                   help="output folder (created; must not hold earlier results)")
    p.add_argument("--overwrite", action="store_true", help="replace results already in --out")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="diffwear", description="Planar mechanisms with clearance and wear in "
                     "their revolute joints: thesis studies, mechanism files and sweeps.",
                     epilog=EXIT_CODES)
    parser.add_argument("--version", action="version", version=f"diffwear {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("study", help="run a named thesis study (see --list)")
    p.add_argument("name", nargs="?", help="study name; omit or use --list to list them")
    p.add_argument("--list", action="store_true", help="list the studies and exit")
    _output_options(p, required=False)
    p.add_argument("--method", choices=WEAR_METHODS,
                   help="wear extrapolation over cycles (wear studies; default constant)")
    p.add_argument("--contact", choices=WEAR_CONTACTS,
                   help="pressure model of the wear (wear studies): efm (default; elastic "
                        "foundation) or fem (finite-element ring loaded by the joint force; "
                        "runs the EFM route too for the comparison)")
    p.add_argument("--model", choices=WEAR_MODELS,
                   help="wear model (wear studies): dynamic (default; the reference) or "
                        "quasi-static (the pin at the equilibrium of the EFM springs: seconds)")
    p.add_argument("--cycles", type=int, default=None,
                   help="number of real crank cycles (wear studies)")
    p.add_argument("--integrator", choices=WEAR_INTEGRATORS,
                   help="integrator of the dynamic cycles (wear studies; both routes): tsit5 "
                        "(explicit, rtol 1e-6; the default of wear-5000) or rodas4 (linearly "
                        "implicit, L-stable, rtol 1e-4; the default of rig-21400: several "
                        "times faster "
                        "where the pin stays pressed into the bushing, as on the rig; slower "
                        "than tsit5 at equal accuracy where it flies and impacts; wear within "
                        "4e-3 of tsit5 on the thesis studies)")
    p.add_argument("--resume", metavar="DIR",
                   help="continue the interrupted wear study whose checkpoint.npz is in DIR "
                        "(same study and options); results are written into DIR")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=_study)

    p = sub.add_parser("design", help="solve a bushing design problem (thesis Ch. 8; see --list)")
    p.add_argument("name", nargs="?", help="design problem: two-joint")
    p.add_argument("--list", action="store_true", help="list the design problems and exit")
    _output_options(p, required=False)
    p.add_argument("--model", default=None, metavar="MODEL",
                   help="quasi-static (default): optimise with exact autodiff Jacobians and "
                        "correct on the dynamic model; dynamic: optimise the dynamic model "
                        "itself with central-difference Jacobians (slow)")
    p.add_argument("--quick", action="store_true",
                   help="coarse models (10 quasi-static, 3 dynamic wear steps) and 2 x 2 "
                        "maps, for a smoke run")
    p.add_argument("--steps", type=int, default=None,
                   help="quasi-static wear steps to the limit (5-400; default 40, --quick 10)")
    p.add_argument("--dynamic-steps", type=int, default=None,
                   help="dynamic wear steps to the limit of the faster joint (1-100; default "
                        "10, --quick 3)")
    p.add_argument("--map-points", type=int, default=None,
                   help="life-map grid points per axis (2-50; default 4, --quick 2)")
    p.add_argument("--n-theta", type=int, default=None,
                   help="bushing profile nodes per joint (12-720; default 90)")
    p.add_argument("--problems", default=None, metavar="NAMES",
                   help="comma-separated: equal-life, longest-common-life, least-material, "
                        "robust, or all (default equal-life; equal life is always solved)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=_design)

    p = sub.add_parser("life", help="cycles to the wear limit of one design (thesis Ch. 8), "
                       "with its Jacobian", epilog="Exit codes: 0 success, 2 bad input, "
                       "3 solver failure (or the model does not hold: contact loss).")
    p.add_argument("name", help="life problem: two-joint")
    for v, what in (("d1", "bore diameter of joint 1"), ("d2", "bore diameter of joint 2"),
                    ("h1", "bushing depth of joint 1"), ("h2", "bushing depth of joint 2")):
        p.add_argument(f"--{v}", type=float, default=None, metavar="MM",
                       help=f"{what} [mm] (Table 8-3 box: d 20-70, h 10-50)")
    p.add_argument("--model", default="quasi-static", metavar="MODEL",
                   help="quasi-static (default; exact autodiff Jacobian) or dynamic")
    p.add_argument("--jacobian", action="store_true",
                   help="also d(cyc1, cyc2)/d(d1, d2, h1, h2) in cycles per mm")
    _output_options(p, required=False)
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=_life)

    p = sub.add_parser("run", help="simulate a mechanism file (TOML; see the docs, "
                       "'Mechanism files')",
                       description="Simulate a mechanism file; with --cycles also the wear of "
                       "every clearance joint that has a wear law (quasi-static model, or "
                       "--model dynamic), with --limit the cycles until its wear reaches that "
                       "depth.",
                       epilog=EXIT_CODES)
    p.add_argument("file", help="mechanism file, or the name of a shipped one: "
                   + ", ".join(shipped_mechanism_names()))
    _output_options(p, required=False)
    p.add_argument("--cycles", type=int, default=None,
                   help="wear every clearance joint with a wear law over N cycles (revolutions "
                        "of the first driver)")
    p.add_argument("--limit", type=float, default=None, metavar="MM",
                   help="with --cycles: also the cycles until each joint's wear reaches MM mm")
    p.add_argument("--model", choices=WEAR_MODELS,
                   help="wear model (with --cycles): quasi-static (default; the pin at the "
                        "equilibrium of the EFM springs: seconds, any number of joints) or "
                        "dynamic (the reference; one wearing joint, checkpointed)")
    p.add_argument("--method", choices=WEAR_METHODS,
                   help="wear extrapolation over cycles of the dynamic model (default constant)")
    p.add_argument("--resume", metavar="DIR",
                   help="continue the interrupted dynamic wear run whose checkpoint.npz is in "
                        "DIR (its cycles, method and limit are read from it)")
    p.add_argument("--yes", action="store_true",
                   help="run a mechanism whose compile is estimated beyond the compile budget "
                        "(10 min on 2 cores; without it such a file is refused with the "
                        "estimate)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=_run)

    p = sub.add_parser("sweep", help="evaluate a model over a parameter grid (TOML; see the docs, "
                       "'Sweeps, sensitivity and clusters')",
                       description="Evaluate a ready-made model (rig-wear, clearance-force) at "
                       "every point of a grid given in a sweep file (on the CPU or the GPU); write "
                       "results.csv/.npz (.nc with SciPy), heatmaps or line plots, summary.json "
                       "and report.md.",
                       epilog="Exit codes: 0 success, 2 bad input, 3 a point failed (results "
                       "are written all the same).")
    p.add_argument("file", help="sweep file, e.g. design_studies/sweep_rig_clearance_k.toml")
    _output_options(p, required=True)
    p.add_argument("--device", choices=SWEEP_DEVICES, default="auto",
                   help="where the points run: cpu (one jitted run after another, over a "
                        "process per core when the first point's time says that pays), gpu "
                        "(vmapped in chunks), auto (default: the GPU when JAX has one)")
    p.add_argument("--chunk-size", type=int, default=None,
                   help="points per vmap call on a GPU (default: the file's [run] chunk_size, "
                        "else all that fit in its memory)")
    p.add_argument("--cluster", metavar="ADDRESS", default=None,
                   help="run on the Dask scheduler at ADDRESS (tcp://host:8786); needs the "
                        "'cluster' extra")
    p.add_argument("--workers", type=int, default=None,
                   help="run on a local Dask cluster of N worker processes (cluster extra)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=_sweep)

    p = sub.add_parser("calibrate", help="fit the rig model to measured wear data and identify "
                       "a missing effect (see the docs, 'Calibration')",
                       description="Fit the dataset's uncertain parameters through the rig "
                       "model (quasi-static by default: exact forward-mode Jacobians; "
                       "Levenberg-Marquardt), select the effects the data show by forward "
                       "selection (every candidate refitted in the form the data determine; "
                       "two equally good candidates reported as such), name the mechanism "
                       "parameter the data ask for when no effect explains them, learn and "
                       "name a discrepancy of the wear coefficient beside the library's "
                       "effects, all on the fit data alone; state each effect's detection "
                       "limit, check the result on the dynamic model, give the posterior, "
                       "the predictive bands, the life with its band and the next "
                       "measurement, and report the held-out error before and after: "
                       "report.md, summary.json, residuals.csv, plots.",
                       epilog="Exit codes: 0 success, 2 bad input, 3 solver failure.")
    p.add_argument("data", help="dataset folder (dataset.toml + CSV files), e.g. "
                   "design_studies/calibration/synthetic_run_in")
    _output_options(p, required=True)
    p.add_argument("--top", type=int, default=3,
                   help="kept for compatibility: every candidate is refitted at each stage")
    p.add_argument("--discrepancy", default="all", metavar="VARIABLES",
                   help="variables over which a learned discrepancy of k is a candidate "
                        "beside the library's effects: comma-separated from angle, "
                        "pressure, sliding_speed, cycles, depth; 'all' (default) or 'none'")
    p.add_argument("--model", choices=CALIBRATION_MODELS, default="quasi-static",
                   help="the forward model fitted (default quasi-static; dynamic: the "
                        "reference, minutes per fit step on a long campaign)")
    p.add_argument("--dynamic-cycles", type=int, default=None,
                   help="dynamic cycles of the dynamic model (default: the fewest with A <= 250)")
    p.add_argument("--no-dynamic-check", action="store_true",
                   help="skip evaluating the final fit on the dynamic model")
    p.add_argument("--n-theta", type=int, default=90, help="profile grid nodes (default 90)")
    p.add_argument("--posterior", choices=("laplace", "nuts"), default="laplace",
                   help="the posterior of the chosen model's numbers: laplace (default: the "
                        "Gaussian at the fit, checked by importance sampling on the exact "
                        "model) or nuts (the No-U-Turn sampler; minutes)")
    p.add_argument("--limit", type=float, default=None, metavar="MM",
                   help="maximum wear depth [mm] that ends the life (default: the bushing wall)")
    p.add_argument("--horizon", type=float, default=None, metavar="CYCLES",
                   help="cycle count up to which the depth is forecast and the next inspection "
                        "is sought (default: twice the last inspection)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=_calibrate)
    return parser


COMPILATION_CACHE = "DIFFWEAR_COMPILATION_CACHE"
"""Environment variable: the folder of the commands' compiled programs
(default ``$XDG_CACHE_HOME/diffwear/jax``, else ``~/.cache/diffwear/jax``),
or ``off``."""


def _compilation_cache(jax) -> None:
    """Keep what the command compiles on disk (JAX's persistent compilation
    cache), so that a second run of the same study or file, or of one that
    differs only in numbers, skips the compiles that take most of a first
    run's time (the lubricated four-bar's wear: ~1 min of 2 on 2 cores).
    JAX keys each program on its code, shapes, options and JAX version; a
    cache that cannot be written only warns."""
    where = os.environ.get(COMPILATION_CACHE, "")
    if where.strip().lower() == "off":
        return
    if not where:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        where = os.path.join(base, "diffwear", "jax")
    jax.config.update("jax_compilation_cache_dir", where)
    # programs that compile in under a second are not worth a file
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    import jax

    jax.config.update("jax_enable_x64", True)  # the library leaves this to its caller
    _compilation_cache(jax)
    import matplotlib

    matplotlib.use("Agg")  # the command writes figures to files; no window
    from .. import interrupt
    from ..io import _OPEN, output_error, release_all

    previous = interrupt.install()
    try:
        code = args.func(args)
        if interrupt.requested():  # pressed, and lost inside a callback: still an interrupt
            print(INTERRUPTED_AT_THE_END, file=sys.stderr)
            return 130
        return code
    except DiffwearError as err:
        print(f"diffwear: error: {err}", file=sys.stderr)
        return err.exit_code
    except KeyboardInterrupt:
        print(_interrupted(args, tuple(_OPEN)), file=sys.stderr)
        for out in _OPEN:  # a run that wrote part of its results: marked as such
            if out.files:
                out.mark_incomplete("the run was interrupted (Ctrl-C) before it finished")
        return 130
    except OSError as err:  # a figure or archive write that failed (a full disk)
        target = _OPEN[-1].abandon_last() if _OPEN and err.errno in _DISK_ERRNOS else None
        if target is None:
            raise
        failed = output_error(err, target)
        _OPEN[-1].mark_incomplete(str(failed))
        print(f"diffwear: error: {failed}", file=sys.stderr)
        return failed.exit_code
    finally:
        release_all()
        interrupt.restore(previous)


def entry() -> None:
    """The ``diffwear`` console command: `main`, then the exit.

    Once `main` returns, a Ctrl-C is only recorded (a run that finished and
    wrote its results is reported as interrupted, exit 130), and the process
    ends with the exit handlers run but without the interpreter's teardown:
    the teardown raced XLA's threads still winding down (a segmentation fault
    after the message), and it restores SIGINT's default action first, so a
    late Ctrl-C killed the process without a word (exit -2).
    """
    from .. import interrupt

    try:
        code = main()
    except KeyboardInterrupt:  # between main's own handling and the hold below
        print(INTERRUPTED, file=sys.stderr)
        code = 130
    except SystemExit as stop:  # the parser's --help and usage errors
        code = _exit_code(stop)
    finally:
        interrupt.hold()
    atexit._run_exitfuncs()
    if code == 0 and interrupt.requested():
        print(INTERRUPTED_AT_THE_END, file=sys.stderr)
        code = 130
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe (`diffwear ... | head`)
            pass
    os._exit(code)


def _exit_code(stop: SystemExit) -> int:
    if stop.code is None or isinstance(stop.code, int):
        return stop.code or 0
    print(stop.code, file=sys.stderr)
    return 1

