"""capmap: keep a manipulator working when things go wrong or space is tight.

Layout (a shared core, one subpackage per method family, I/O at the edges):

- :mod:`capmap.core`       robot models, joint locking, kinematics, IK, dynamics, branch
                           tracking, speed profiles, affine limits (pure numerics)
- :mod:`capmap.capacity`   family 1: capacity map, A* planning, verification
- :mod:`capmap.following`  family 2: torque-limited path following vs TOPP-RA
- :mod:`capmap.config`     config and robot files -> frozen dataclasses; stage slices; checks
- :mod:`capmap.io`         Parquet datasets with provenance, tables, logging
- :mod:`capmap.stages`     what each Snakemake rule runs (file I/O lives here)
- :mod:`capmap.plots`      figures, one module per family
- :mod:`capmap.errors`     the one-line exception hierarchy

Dependencies point one way: core <- families <- config <- stages; io and errors are
below everything, plots only read DataFrames.
"""

__version__ = "0.1.0"
__all__ = ["load", "catalogue", "numba_folder"]


def load(run: str = "default", name: str = "voxels", results: str = "results"):
    """A dataset of a run as a pandas DataFrame: ``capmap.load("default", "voxels")`` (the names:
    ``capmap.catalogue("default")``; docs/outputs.md). See :func:`capmap.io.catalogue.load`."""
    from capmap.io.catalogue import load as _load

    return _load(run, name, results)


def catalogue(run: str = "default", results: str = "results"):
    """The datasets of a run (name, description, what a row is, path, rows, columns with units) as a
    DataFrame. See :func:`capmap.io.catalogue.catalogue`."""
    from capmap.io.catalogue import catalogue as _catalogue

    return _catalogue(run, results)


def numba_folder(package, base: str) -> str:
    """The cache folder under ``base`` for the compiled sources (the files with ``import numba`` at the start
    of a line: the kernels' modules) of ``package`` (a folder): named by their content."""
    import hashlib
    import re
    from pathlib import Path

    h = hashlib.sha256()
    for f in sorted(Path(package).rglob("*.py")):
        text = f.read_bytes()
        if re.search(rb"^import numba", text, re.MULTILINE):
            h.update(str(f.relative_to(package)).encode() + b"\0" + text)
    return str(Path(base) / f"numba-{h.hexdigest()[:16]}")


def _numba_cache_dir() -> None:
    """Numba's on-disk cache in a folder per content of capmap's compiled sources (:func:`numba_folder`),
    shared by every checkout on the machine (:mod:`capmap._numba_cache`: kernels named by their place in
    the package and stamped by content, not by path and time). Numba checks a cached function against
    its own file only, not the functions it calls in other files, so an edit of a callee (the dual-arm
    node kernel, called by the compiled FDDP) would leave its callers' cached code stale; a new folder
    per content recompiles everything instead (``python -m capmap.kernels`` warms it). Under
    NUMBA_CACHE_DIR when set, else the user's cache folder (``$XDG_CACHE_HOME/capmap`` or
    ``~/.cache/capmap``) when writable, else the package's __pycache__. Set before numba is imported
    (numba reads it then), or in numba's config after."""
    import os
    import sys
    from pathlib import Path

    package = Path(__file__).resolve().parent
    given = os.environ.get("NUMBA_CACHE_DIR")
    if given and given == os.environ.get("CAPMAP_NUMBA_DIR"):  # inherited from a parent that imported capmap
        base = os.environ["CAPMAP_NUMBA_BASE"]
    elif given:
        base = given
    else:
        user = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "capmap"
        try:
            user.mkdir(parents=True, exist_ok=True)
            writable = os.access(user, os.W_OK)
        except OSError:
            writable = False
        base = str(user) if writable else str(package / "__pycache__")
    folder = numba_folder(package, base)
    locators = os.environ.get("NUMBA_CACHE_LOCATOR_CLASSES") or \
        "capmap._numba_cache.ContentLocator,UserProvidedCacheLocator,InTreeCacheLocator,UserWideCacheLocator"
    os.environ.update(NUMBA_CACHE_DIR=folder, CAPMAP_NUMBA_BASE=base, CAPMAP_NUMBA_DIR=folder,
                      NUMBA_CACHE_LOCATOR_CLASSES=locators)
    if "numba" in sys.modules:
        sys.modules["numba"].config.CACHE_DIR = folder
        sys.modules["numba"].config.CACHE_LOCATOR_CLASSES = locators


_numba_cache_dir()
