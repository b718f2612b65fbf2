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
"""

from __future__ import annotations

import ast
import hashlib
from functools import lru_cache
from pathlib import Path

import capmap

__all__ = ["code_fingerprint", "script_fingerprint", "module_closure", "file_fingerprints", "file_sha256"]

_SRC = Path(capmap.__file__).resolve().parent


def _module_file(name: str) -> Path | None:
    """The source file of module ``capmap.x.y`` (a package's ``__init__.py``), or None."""
    parts = name.split(".")[1:]
    base = _SRC.joinpath(*parts)
    for cand in (base.with_suffix(".py"), base / "__init__.py"):
        if cand.is_file():
            return cand
    return None


def _imports(name: str, tree: ast.Module) -> set[str]:
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.split(".")[0] == "capmap"}
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative import
                pkg = name.split(".")[: -node.level] if not _module_file(name).name == "__init__.py" else name.split(".")
                mod = ".".join(pkg + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            if mod.split(".")[0] != "capmap":
                continue
            subs = {f"{mod}.{a.name}" for a in node.names if _module_file(f"{mod}.{a.name}")}
            out |= subs
            if len(subs) < len(node.names):  # names defined or re-exported by mod itself
                out.add(mod)
    return out


def _tree(path: Path) -> ast.Module:
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):  # docstrings carry no behaviour
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) and \
                isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
            node.body = body[1:] or [ast.Pass()]
    return tree


@lru_cache(maxsize=None)
def module_closure(name: str) -> tuple[str, ...]:
    """The capmap modules ``name`` imports, transitively, sorted. A package's ``__init__`` counts
    with its own code; its re-exports are followed only where names are imported from the
    package itself (``from capmap.config import canonical``), not where a submodule is
    (``from capmap.config.failure import ...``): a stage depends on what it uses."""
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
    """16 hex digits of the syntax trees (no docstrings) of every capmap module ``name`` runs."""
    h = hashlib.sha256()
    for mod in module_closure(name):
        h.update(mod.encode())
        h.update(_module_digest(mod))
    return h.hexdigest()[:16]


@lru_cache(maxsize=None)
def script_fingerprint(path: str | Path) -> str:
    """16 hex digits of a Snakemake script (its syntax tree: not its comments) and of every capmap
    module it runs (:func:`code_fingerprint` of each module it imports)."""
    tree = _tree(Path(path))
    h = hashlib.sha256(ast.dump(tree).encode())
    mods = sorted(_imports("__main__", tree))
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
