"""Lazy package exports (PEP 562): a subpackage lists what it offers in ``__all__`` but imports
a module only when one of its names is first used, so that a Snakemake job importing one stage
does not pay for every family's imports (matplotlib, scipy.cluster, Crocoddyl ...)."""

from __future__ import annotations

import importlib

__all__ = ["lazy_exports"]


def lazy_exports(package: str, exports: dict[str, str]):
    """``exports``: public name -> the submodule (relative to ``package``) that defines it, or
    the submodule itself when name == submodule. Returns (__getattr__, __dir__) for the package."""

    def __getattr__(name: str):
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        mod = importlib.import_module(f"{package}.{module}")
        return mod if name == module else getattr(mod, name)

    def __dir__():
        return sorted(exports)

    return __getattr__, __dir__
