"""What a stage depends on besides its config: the package code it runs and the content of the
files it reads. Both go into the rule's params (so Snakemake reruns a stage when either
changes, and not when only a file's date or a comment changes) and into the provenance of
every dataset the stage writes.

- :func:`code_fingerprint`: a hash of the modules of ``capmap`` that a stage module imports,
  transitively, each reduced to its syntax tree without docstrings (comments and formatting
  never reach the tree), so a change of the numerics reruns the stage and a reworded comment
  does not.
- :func:`file_fingerprints`: sha256 of files by content (a file restored with an old date is
  still a change when its content differs).

Imports are followed from the syntax tree, so a name a package face (:mod:`capmap._lazy`)
resolves only when first used is followed through the package's ``_EXPORTS`` dict literal
(name -> the submodule that defines it), parsed from its ``__init__``:

- ``from capmap.capacity import point_capacity`` counts ``capmap.capacity`` and
  ``capmap.capacity.engine``; ``from capmap.capacity import *`` every submodule ``_EXPORTS`` names.
- A package face imported as a module (``import capmap.capacity as c``, ``from capmap import
  capacity``) counts conservatively with every submodule its ``_EXPORTS`` names, as code may
  reach any of them through attributes (``c.point_capacity``). The parents of a dotted import
  (``capmap.capacity`` of ``import capmap.capacity.engine``) count with their own code only.
- A package whose ``__init__`` defines or assigns a module-level ``__getattr__`` without an
  ``_EXPORTS`` dict literal of strings can resolve any name: every submodule in its folder counts.
"""

from __future__ import annotations

import ast
import hashlib
import json
import os
import sys
from functools import lru_cache
from pathlib import Path

import capmap

__all__ = ["code_fingerprint", "script_fingerprint", "script_modules", "module_closure", "file_fingerprints", "file_sha256",
           "package_hash"]

_SRC = Path(capmap.__file__).resolve().parent


def _module_file(name: str) -> Path | None:
    """The source file of module ``capmap.x.y`` (a package's ``__init__.py``), or None."""
    parts = name.split(".")[1:]
    base = _SRC.joinpath(*parts)
    for cand in (base.with_suffix(".py"), base / "__init__.py"):
        if cand.is_file():
            return cand
    return None


def _type_checking(node: ast.AST) -> bool:
    """``if TYPE_CHECKING:`` (or ``typing.TYPE_CHECKING``): imports for annotations only, never run."""
    t = getattr(node, "test", None)
    return isinstance(node, ast.If) and (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING" or
                                         isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING")


def _run_nodes(tree: ast.AST):
    """Every node of ``tree`` but those under ``if TYPE_CHECKING:`` (their ``else`` is kept)."""
    todo = [tree]
    while todo:
        node = todo.pop()
        yield node
        if _type_checking(node):
            todo.extend(node.orelse)
            continue
        todo.extend(ast.iter_child_nodes(node))


def _imports(name: str, tree: ast.Module) -> set[str]:
    out = set()
    for node in _run_nodes(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                if a.name.split(".")[0] == "capmap":
                    out |= {a.name} | _lazy_targets(a.name, "*")
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative import
                pkg = name.split(".")[: -node.level] if not _module_file(name).name == "__init__.py" else name.split(".")
                mod = ".".join(pkg + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            if mod.split(".")[0] != "capmap":
                continue
            for a in node.names:
                sub = f"{mod}.{a.name}"
                if _module_file(sub):
                    out |= {sub} | _lazy_targets(sub, "*")
                else:  # a name defined or re-exported by mod itself, or resolved lazily from a submodule
                    out |= {mod} | _lazy_targets(mod, a.name)
    return out


@lru_cache(maxsize=None)
def _lazy_exports(mod: str) -> dict[str, str] | None:
    """A package face's names and the submodules defining them: its ``_EXPORTS`` dict literal of
    strings; {} when it resolves no names lazily (no module-level ``__getattr__``); None when it does
    but the dict cannot be read from the syntax tree."""
    path = _module_file(mod)
    if path is None or path.name != "__init__.py":
        return {}
    lazy = False
    for node in _module_tree(mod).body:
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(node, ast.AnnAssign) else []
        names = {n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)}
        if "_EXPORTS" in names and isinstance(node.value, ast.Dict):
            try:
                exports = ast.literal_eval(node.value)
            except ValueError:
                continue
            if all(isinstance(k, str) and isinstance(v, str) for k, v in exports.items()):
                return exports
        lazy |= "__getattr__" in names or (isinstance(node, ast.FunctionDef) and node.name == "__getattr__")
    return None if lazy else {}


def _lazy_targets(mod: str, name: str) -> set[str]:
    """The submodules of package ``mod`` that importing ``name`` from it may run (``*``: any of its names)."""
    exports = _lazy_exports(mod)
    if exports is None:  # unreadable exports: every submodule in the package's folder
        folder = _module_file(mod).parent
        subs = {p.stem for p in folder.glob("*.py") if p.name != "__init__.py"}
        subs |= {p.parent.name for p in folder.glob("*/__init__.py")}
    else:
        subs = set(exports.values()) if name == "*" else {exports[name]} if name in exports else set()
    return {f"{mod}.{s}" for s in subs if _module_file(f"{mod}.{s}")}


def _tree(path: Path) -> ast.Module:
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):  # docstrings carry no behaviour
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) and \
                isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
            node.body = body[1:] or [ast.Pass()]
    return tree


@lru_cache(maxsize=None)
def _source_hash() -> str:
    """16 hex digits of every capmap source file (path and content) and the Python version (its syntax
    trees' dump format): the key of the disk cache."""
    h = hashlib.sha256(sys.version.encode())
    for f in sorted(_SRC.rglob("*.py")):
        h.update(str(f.relative_to(_SRC)).encode() + b"\0" + f.read_bytes())
    return h.hexdigest()[:16]


def package_hash() -> str:
    """16 hex digits of every capmap source file and the Python version: what a warm process of this
    code is keyed by."""
    return _source_hash()


def _cache_file() -> Path:
    return _SRC / "__pycache__" / f"fingerprints-{_source_hash()}.json"


@lru_cache(maxsize=None)
def _disk() -> dict:
    """Closures and fingerprints computed by an earlier process for exactly these sources (a Snakemake
    invocation parses ~150 modules otherwise: ~2.5 s); {} when there is none or it is unreadable."""
    try:
        return json.loads(_cache_file().read_text())
    except (OSError, ValueError):
        return {}


def _remember(key: str, value) -> None:
    """Store a result in the disk cache (atomically; older caches removed; a read-only install keeps none)."""
    cache = _disk()
    cache[key] = value
    path = _cache_file()
    try:
        path.parent.mkdir(exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(cache))
        os.replace(tmp, path)
        for old in path.parent.glob("fingerprints-*.json"):
            if old != path:
                old.unlink(missing_ok=True)
    except OSError:
        pass


@lru_cache(maxsize=None)
def module_closure(name: str) -> tuple[str, ...]:
    """The capmap modules ``name`` imports, transitively, sorted. A package's ``__init__`` counts
    with its own code; its re-exports are followed only where names are imported from the
    package itself (``from capmap.config import canonical``), not where a submodule is
    (``from capmap.config.failure import ...``): a stage depends on what it uses. Cached on disk per
    version of the sources."""
    if f"closure:{name}" in _disk():
        return tuple(_disk()[f"closure:{name}"])
    out = _module_closure(name)
    _remember(f"closure:{name}", list(out))
    return out


def _module_closure(name: str) -> tuple[str, ...]:
    seen, expanded, todo = set(), set(), [name]
    while todo:
        mod = todo.pop()
        if _module_file(mod) is None or mod in expanded:
            continue
        expanded.add(mod)
        parts = mod.split(".")
        seen |= {".".join(parts[:k]) for k in range(1, len(parts) + 1) if _module_file(".".join(parts[:k]))}
        todo.extend(_module_imports(mod))
    return tuple(sorted(seen))


@lru_cache(maxsize=None)
def _module_tree(mod: str) -> ast.Module:
    """A module's syntax tree without docstrings, parsed once per process (its imports are intact)."""
    return _tree(_module_file(mod))


@lru_cache(maxsize=None)
def _module_imports(mod: str) -> frozenset[str]:
    return frozenset(_imports(mod, _module_tree(mod)))


@lru_cache(maxsize=None)
def _module_digest(mod: str) -> bytes:
    """sha256 of a module's syntax tree without docstrings."""
    return hashlib.sha256(ast.dump(_module_tree(mod)).encode()).digest()


@lru_cache(maxsize=None)
def code_fingerprint(name: str) -> str:
    """16 hex digits of the syntax trees (no docstrings) of every capmap module ``name`` runs (cached on
    disk per version of the sources)."""
    if f"code:{name}" in _disk():
        return _disk()[f"code:{name}"]
    h = hashlib.sha256()
    for mod in module_closure(name):
        h.update(mod.encode())
        h.update(_module_digest(mod))
    _remember(f"code:{name}", h.hexdigest()[:16])
    return h.hexdigest()[:16]


def script_modules(path: str | Path) -> set[str]:
    """The capmap modules a Snakemake script runs: those it imports, and the module of the function it names
    (``call("capmap.stages.x:stage_y", ...)``, :func:`capmap.io.logs.call`: imported when it runs, by the
    job or by the run's job server)."""
    tree = _tree(Path(path))
    return _imports("__main__", tree) | _targets(tree)


def _targets(tree: ast.Module) -> set[str]:
    out = set()
    for node in ast.walk(tree):
        if (isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant)
                and isinstance(node.args[0].value, str) and node.args[0].value.startswith("capmap.")
                and ":" in node.args[0].value):
            out.add(node.args[0].value.split(":")[0])
    return out


def script_fingerprint(path: str | Path, also: tuple[str, ...] | list[str] = ()) -> str:
    """16 hex digits of a Snakemake script (its syntax tree: not its comments) and of every capmap
    module it runs (:func:`code_fingerprint` of each module it imports, and of the modules ``also``
    names: those a job imports by name at run time, e.g. the config sections its slice holds)."""
    return _script_fingerprint(str(path), tuple(sorted(set(also))))


@lru_cache(maxsize=None)
def _script_fingerprint(path: str, also: tuple[str, ...]) -> str:
    tree = _tree(Path(path))
    h = hashlib.sha256(ast.dump(tree).encode())
    mods = sorted(_imports("__main__", tree) | _targets(tree) | set(also))
    for mod in mods:
        h.update(code_fingerprint(mod).encode())
    return h.hexdigest()[:16]


def file_sha256(path: str | Path) -> str:
    """sha256 of a file's content (hex)."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def file_fingerprints(paths) -> dict[str, str]:
    """{name: first 16 hex digits of its sha256} for the given files. A relative path is its own
    name; an absolute one (e.g. a URDF inside an installed package) is named by its last three
    parts, so the same files give the same fingerprints on any machine."""
    out = {}
    for p in sorted(set(map(str, paths))):
        name = p if not Path(p).is_absolute() else ".../" + "/".join(Path(p).parts[-3:])
        out[name] = file_sha256(p)[:16]
    return out
