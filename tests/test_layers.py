"""The package's import graph: acyclic at module level (every import counted,
those inside functions too, so no cycle hides behind a lazy import) and no
module-level ``__getattr__`` import tricks."""

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "diffwear"


def _module_name(path: Path) -> str:
    rel = path.relative_to(SRC.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _imports(path: Path, name: str) -> set[str]:
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("diffwear"):
                # "from .pkg import mod" imports the submodule when it is one
                for alias in node.names:
                    sub = f"{target}.{alias.name}"
                    found.add(sub if sub in MODULES else target)
        elif isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.startswith("diffwear"))
    return {m for m in found if m in MODULES and m != name}


MODULES = {_module_name(p): p for p in SRC.rglob("*.py")}


def _graph() -> dict[str, set[str]]:
    graph = {}
    for name, path in MODULES.items():
        deps = set()
        for d in _imports(path, name):
            # importing a module runs its packages' __init__ files first
            parts = d.split(".")
            deps.update(".".join(parts[:i]) for i in range(2, len(parts) + 1))
        graph[name] = {d for d in deps if d in MODULES and d != name
                       and not name.startswith(d + ".")}
    return graph


def test_module_imports_are_acyclic():
    graph = _graph()
    state: dict[str, int] = {}
    stack: list[str] = []
    cycles = []

    def visit(node):
        state[node] = 1
        stack.append(node)
        for dep in sorted(graph[node]):
            if state.get(dep) == 1:
                cycles.append(stack[stack.index(dep):] + [dep])
            elif dep not in state:
                visit(dep)
        stack.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node)
    assert not cycles, "\n".join(" -> ".join(c) for c in cycles)


def test_no_module_getattr_import_tricks():
    tricks = [name for name, path in MODULES.items()
              if any(isinstance(n, ast.FunctionDef) and n.name == "__getattr__"
                     for n in ast.parse(path.read_text()).body)]
    assert not tricks, tricks


# The package's layers, bottom to top: a module imports only from its own
# package or from a lower layer (peers in one layer do not import each other).
LAYERS = (
    ("errors",),                          # the error classes
    ("report",),                          # reports as data and their renderer
    ("choices", "_checks", "io", "gradient_check", "interrupt",  # options, outputs,
     "worker", "progress"),               # worker processes, a long wait's progress line
    ("mechanism",),                       # bodies, joints, forces: the DAE's terms
    ("dynamics", "contact", "fem"),       # integration; contact laws; FEM contact
    ("wear",),                            # Archard wear, the profile, the evolution
    ("quasistatic",),                     # the quasi-static joint model
    ("models",),                          # the wear models: dynamic, quasi-static, FEM
    ("presets",),                         # the thesis mechanisms in code
    ("sweep", "plots"),                   # the sweep engine; figures from plain data
    ("studies",),                         # the thesis studies
    ("config",),                          # input formats: mechanism and sweep files
    ("mechanism_file",),                  # a loaded mechanism file, run whole
    ("calibrate", "design"),              # fitting to data; the bushing design
    ("cli", "_worker_entry"),             # the command; a worker process's entry point
)


def test_imports_follow_the_layers():
    rank = {pkg: i for i, layer in enumerate(LAYERS) for pkg in layer}

    def package(module: str) -> str:
        return module.split(".")[1] if "." in module else module

    unplaced = sorted({package(m) for m in MODULES if "." in m} - set(rank))
    assert not unplaced, f"place these in LAYERS: {unplaced}"
    upward = sorted((m, d) for m, deps in _graph().items() if "." in m for d in deps
                    if "." in d and package(d) != package(m)
                    and rank[package(d)] >= rank[package(m)])
    assert not upward, "\n".join(f"{m} -> {d}" for m, d in upward)


def test_only_the_models_and_the_wear_package_import_the_engine():
    """The wear engine is private: every way into it is a model's ``solve``.
    Its importers in the package are the models and the wear package itself;
    the tests, benchmarks and studies reach it through `diffwear.models`."""
    engine = "diffwear.wear._engine"
    importers = sorted(m for m, path in MODULES.items() if engine in _imports(path, m))
    assert importers and all(m.startswith(("diffwear.models", "diffwear.wear"))
                             for m in importers), importers
    root = SRC.parents[1]
    outside = [str(p.relative_to(root)) for folder in ("tests", "benchmarks", "design_studies")
               for p in (root / folder).rglob("*.py")
               if "wear._engine" in p.read_text() or "wear.engine" in p.read_text()]
    assert outside == [str(Path(__file__).relative_to(root))], outside


def test_the_core_does_not_import_the_command_line_layer():
    """mechanism, dynamics, contact, fem, wear and quasistatic never import the
    studies, drivers, plots or the CLI."""
    core = ("mechanism", "dynamics", "contact", "fem", "wear", "quasistatic")
    upper = ("diffwear.cli", "diffwear.studies", "diffwear.plots", "diffwear.mechanism_file",
             "diffwear.design", "diffwear.calibrate", "diffwear.sweep")
    graph = _graph()
    bad = [(m, d) for m, deps in graph.items() for d in deps
           if m.split(".")[1:2] and m.split(".")[1] in core and d.startswith(upper)]
    assert not bad, bad


def test_import_leaves_float64_to_the_caller_and_models_say_so():
    """``import diffwear`` does not switch JAX's process-wide float64 flag; a
    simulation without it raises InputError naming the fix (a fresh
    interpreter: this test process has float64 on)."""
    import subprocess
    import sys

    code = (
        "import jax, diffwear\n"
        "assert not jax.config.jax_enable_x64\n"
        "from diffwear.presets import TABLE_2_1, slider_crank\n"
        "mech, q = slider_crank(TABLE_2_1)\n"
        "try:\n"
        "    diffwear.simulate(mech, diffwear.consistent_state(mech, q), 0.1)\n"
        "except diffwear.InputError as err:\n"
        "    assert 'jax_enable_x64' in str(err), err\n"
        "    print('refused')\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={**__import__("os").environ, "PYTHONPATH": str(SRC.parent)})
    assert out.returncode == 0 and "refused" in out.stdout, out.stderr[-2000:]


def test_public_names_do_not_hide_subpackages():
    """``import diffwear.x.y`` resolves through attributes: a top-level function
    named like a subpackage (``sweep``, ``calibrate``) would hide it."""
    import importlib
    import types

    import diffwear

    for name in diffwear.__all__:
        if (SRC / name).is_dir() or (SRC / f"{name}.py").is_file():
            assert isinstance(getattr(diffwear, name), types.ModuleType), name
            assert getattr(diffwear, name) is importlib.import_module(f"diffwear.{name}")


def test_only_the_command_line_chooses_the_matplotlib_backend():
    """A library import never switches the user's backend (a notebook keeps
    its inline one); the ``diffwear`` command selects Agg itself."""
    chooses = [name for name, path in MODULES.items() if "matplotlib.use(" in path.read_text()]
    assert chooses == ["diffwear.cli.command"], chooses
