"""Numba's cache keyed by content, not by checkout: compile once per machine.

Numba's own locators name a cached function by its source file's absolute path and stamp it with the
file's modification time, so a second checkout of the same code (or a fresh clone, whose files are all
new) compiles every kernel again. :class:`ContentLocator` names it by the file's path inside the capmap
package and stamps it with the file's content, so every checkout of the same code on a machine shares
one cache (``capmap._numba_cache_dir`` puts it under the user's cache folder, in a folder per content
of all the compiled sources: an edit of a callee in another file cannot leave a caller stale). Numba
finds it through ``NUMBA_CACHE_LOCATOR_CLASSES``, which capmap sets before numba is imported."""

from __future__ import annotations

import hashlib
import os
from functools import lru_cache
from pathlib import Path

from numba.core import config
from numba.core.caching import _CacheLocator, _SourceFileBackedLocatorMixin

__all__ = ["ContentLocator", "PACKAGE"]

PACKAGE = Path(__file__).resolve().parent


@lru_cache(maxsize=None)
def _content(path: str) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


class ContentLocator(_SourceFileBackedLocatorMixin, _CacheLocator):
    """A capmap kernel's cache: ``<CACHE_DIR>/capmap/<its folder in the package>``, stamped by content."""

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        rel = Path(py_file).resolve().relative_to(PACKAGE).parent
        self._cache_path = os.path.join(config.CACHE_DIR, "capmap", *rel.parts)

    def get_cache_path(self):
        return self._cache_path

    def get_source_stamp(self):
        return _content(str(Path(self._py_file).resolve()))

    @classmethod
    def from_function(cls, py_func, py_file):
        if not config.CACHE_DIR or not Path(py_file).resolve().is_relative_to(PACKAGE):
            return None  # not capmap's: numba's own locators
        return super().from_function(py_func, py_file)
