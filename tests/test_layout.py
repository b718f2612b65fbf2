"""The package layout as a contract: small modules, no import cycles, dependencies one way,
``__all__`` everywhere, and no capmap imports hidden inside functions."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "capmap"
MAX_LINES = 350

# what each part of the package may import (besides itself and the standard/third-party libraries)
ALLOWED = {
    "errors": set(),
    "core": {"errors"},
    "capacity": {"core", "config", "robots", "errors"},  # config: only in its build modules (BUILDERS)
    "following": {"core", "config", "robots", "errors"},  # config: only in its build module
    "reconfig": {"core", "config", "robots", "errors"},  # config: only in its build module
    "dualarm": {"core", "config", "robots", "errors"},  # config: only in its build module
    "io": {"errors"},
    # config is data: it imports no numerics (test_config_is_data)
    "config": {"core", "following", "reconfig", "dualarm", "io", "errors"},
    # the pre-run checks that need the robot: through each family's build module
    "checks": {"core", "capacity", "following", "reconfig", "dualarm", "config", "robots", "io", "errors"},
    # robot files -> robots (the file checks in config, the models in core); read by the build modules
    "robots": {"core", "config", "errors"},
    "plots": set(),
    "stages": {"core", "capacity", "following", "reconfig", "dualarm", "config", "robots", "checks", "io", "plots",
               "errors"},
    # the command line (python -m capmap check, check-config, arm; query: a stage, as a workflow script calls one)
    "__main__": {"config", "robots", "checks", "io", "stages", "errors"},
    # compile the numba kernels once before the jobs (python -m capmap.kernels): each family's compiled calls
    "kernels": {"core", "capacity", "dualarm", "config", "robots", "checks", "io", "errors"},
    "_lazy": set(),  # lazy package exports (PEP 562): any package may use it
}
NUMERICS = {"core", "capacity", "following", "reconfig", "dualarm"}
# where a family turns its config sections into numerics: the only modules of a family that import config
BUILDERS = {"capmap.capacity.build", "capmap.capacity.build_healthy", "capmap.capacity.sizing", "capmap.reconfig.build",
            "capmap.following.build", "capmap.dualarm.build", "capmap.reconfig.platform_file",
            "capmap.dualarm.scene_file"}  # (and their files)
for _part_name in ALLOWED:
    ALLOWED[_part_name] = ALLOWED[_part_name] | {"_lazy"}


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(SRC.rglob("*.py")):
        parts = path.relative_to(SRC.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    return out


MODULES = _modules()


def _imports(path: Path) -> list[tuple[str, bool]]:
    """(imported capmap module, at module level?) for every import of capmap in a file."""
    tree = ast.parse(path.read_text())
    top = set(map(id, tree.body))
    for node in tree.body:  # ``if TYPE_CHECKING:`` imports (annotations only) count as top-level ones
        if isinstance(node, ast.If) and getattr(node.test, "id", getattr(node.test, "attr", "")) == "TYPE_CHECKING":
            top |= set(map(id, node.body))
    out = []
    for node in ast.walk(tree):
        names = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            # ``from pkg import submodule`` depends on the submodule, ``from mod import name`` on mod
            names = [f"{node.module}.{a.name}" if f"{node.module}.{a.name}" in MODULES else node.module
                     for a in node.names]
        for n in names:
            if n.startswith("capmap."):
                while n not in MODULES and "." in n:
                    n = n.rsplit(".", 1)[0]
                if n in MODULES:
                    out.append((n, id(node) in top))
    return out


def _part(module: str) -> str:
    return module.split(".")[1] if module.count(".") else "__init__"


@pytest.mark.parametrize("name", sorted(MODULES))
def test_module_is_small(name):
    n = len(MODULES[name].read_text().splitlines())
    assert n <= MAX_LINES, f"{name} has {n} lines (limit {MAX_LINES})"


# modules that import a family inside the function that needs it: the command line (``capmap --help`` and a
# usage error answer at once, ``capmap query`` does not load the dual-arm family) and the pre-run checks of the
# families a capacity query does not check. Each import still points the allowed way.
IMPORT_WHEN_USED = {"capmap.__main__", "capmap.checks"}


@pytest.mark.parametrize("name", sorted(m for m in MODULES if m.count(".")))
def test_imports_point_one_way_and_sit_at_the_top(name):
    part = _part(name)
    for imported, at_top in _imports(MODULES[name]):
        assert at_top or name in IMPORT_WHEN_USED, f"{name} imports {imported} inside a function"
        other = _part(imported)
        if other != part:
            assert other in ALLOWED[part], f"{name} ({part}) must not import {imported} ({other})"


def test_no_import_cycles():
    graph = {m: {i for i, _ in _imports(p) if i != m} for m, p in MODULES.items()}
    state: dict[str, int] = {}

    def visit(m, stack):
        state[m] = 1
        for n in graph[m]:
            if state.get(n) == 1:
                raise AssertionError(" -> ".join(stack[stack.index(n):] + [m, n]) if n in stack else f"{m} -> {n}")
            if n not in state:
                visit(n, stack + [m])
        state[m] = 2

    for m in graph:
        if m not in state:
            visit(m, [])


@pytest.mark.parametrize("name", sorted(m for m in MODULES if m != "capmap"))
def test_every_module_declares_all(name):
    tree = ast.parse(MODULES[name].read_text())
    assigned = {t.id for node in tree.body if isinstance(node, ast.Assign) for t in node.targets
                if isinstance(t, ast.Name)}
    assert "__all__" in assigned, f"{name} has no __all__"


@pytest.mark.parametrize("name", sorted(m for m in MODULES if _part(m) in NUMERICS))
def test_only_the_build_modules_read_config(name):
    reads = sorted(i for i, _ in _imports(MODULES[name]) if _part(i) in ("config", "robots"))
    assert not reads or name in BUILDERS, f"{name} imports {reads}: config meets numerics in a family's build module"


@pytest.mark.parametrize("name", sorted(m for m in MODULES if _part(m) == "config"))
def test_config_is_data(name):
    numerics = sorted(i for i, _ in _imports(MODULES[name]) if _part(i) in NUMERICS | {"robots"})
    assert not numerics, f"{name} imports {numerics}: config is data (build numerics in the family's build module)"


MAX_FUNCTION_LINES = 80  # a non-kernel function; a numba kernel may be longer where splitting costs speed
MAX_PARAMETERS = 7  # a public non-kernel function's (self and cls not counted): more go into a dataclass
# still over (each to be split or given a parameter object): the lists may only shrink
LONG_LEFT: set[str] = set()
STAGES_LEFT: set[str] = set()
PARAMETERS_LEFT: set[str] = set()
STAGE_LINES = 40  # a stage: read, call one family function, write


def _functions():
    """(qualified name, node, is a numba kernel, is nested) of every function of the package."""
    out = []
    for name, path in MODULES.items():
        tree = ast.parse(path.read_text())

        def visit(node, prefix, nested):
            for child in ast.iter_child_nodes(node):
                if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    decos = " ".join(ast.unparse(d) for d in child.decorator_list)
                    kernel = any(k in decos for k in ("jit", "_inline", "numba"))
                    out.append((f"{prefix}.{child.name}", child, kernel, nested))
                    visit(child, f"{prefix}.{child.name}", True)
                elif isinstance(child, ast.ClassDef):
                    visit(child, f"{prefix}.{child.name}", nested)
        visit(tree, name, False)
    return out


FUNCTIONS = _functions()


def test_functions_are_short():
    long = {q: f.end_lineno - f.lineno + 1 for q, f, kernel, nested in FUNCTIONS
            if not kernel and not nested and f.end_lineno - f.lineno + 1 > MAX_FUNCTION_LINES}
    assert set(long) <= LONG_LEFT, f"over {MAX_FUNCTION_LINES} lines: {sorted(set(long) - LONG_LEFT)}"
    assert not LONG_LEFT - set(long), f"short now, drop from LONG_LEFT: {sorted(LONG_LEFT - set(long))}"


def _n_params(f) -> int:
    a = f.args
    names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs] + [x.arg for x in (a.vararg, a.kwarg) if x]
    return len([n for n in names if n not in ("self", "cls")])


def test_public_functions_take_at_most_seven_parameters():
    many = {q for q, f, kernel, nested in FUNCTIONS if not kernel and not nested and not f.name.startswith("_")
            and _n_params(f) > MAX_PARAMETERS}
    assert many <= PARAMETERS_LEFT, f"over {MAX_PARAMETERS} parameters: {sorted(many - PARAMETERS_LEFT)}"
    assert not PARAMETERS_LEFT - many, f"fixed, drop from PARAMETERS_LEFT: {sorted(PARAMETERS_LEFT - many)}"


def test_stages_are_thin():
    long = {q for q, f, _, nested in FUNCTIONS if q.startswith("capmap.stages.") and f.name.startswith("stage_")
            and f.end_lineno - f.lineno + 1 > STAGE_LINES}
    assert long <= STAGES_LEFT, f"stages over {STAGE_LINES} lines: {sorted(long - STAGES_LEFT)}"
    assert not STAGES_LEFT - long, f"thin now, drop from STAGES_LEFT: {sorted(STAGES_LEFT - long)}"
