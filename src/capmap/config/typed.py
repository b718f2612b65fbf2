"""Typed configuration objects <-> JSON documents, driven by the dataclasses' own type hints.

The run configuration is validated once (JSON schema, then the section parsers of
:mod:`capmap.config.run`) into frozen dataclasses. What a stage depends on travels to the job as
a JSON *slice* of those objects (:mod:`capmap.config.slices`) and comes back as the same types
through :func:`partial`: one generic rebuild, no second hand-written parser. A field the stage did
not declare comes back as :class:`Undeclared`, which raises on any use, so an undeclared
dependency (a cache gap) is an error in the job, not a silently stale result.

Field metadata understood here (``dataclasses.field(metadata=...)``):

- ``FILE``: the field names a file whose content (and the files it names) a slice hashes;
- ``ROUND``: a float or float sequence written rounded to 9 decimals, so that equal resolved
  values (a lock angle, a start resolved by IK) give equal slices.
"""

from __future__ import annotations

import builtins
import dataclasses
import importlib
import sys
import types
import typing
from functools import lru_cache
from typing import Any

import numpy as np

from capmap.errors import CapmapError, ConfigError

__all__ = ["FILE", "ROUND", "Undeclared", "to_doc", "rounded", "partial", "get_path", "field_meta", "file_paths",
           "as_tuple", "per_item"]

FILE = {"file": True}
ROUND = {"round": 9}


class Undeclared:
    """Stands for a config field that is not in a stage's slice: any use raises, naming it (only
    ``x is None`` cannot be trapped: test declared fields, never undeclared ones)."""

    __slots__ = ("path",)

    def __init__(self, path: str):
        object.__setattr__(self, "path", path)

    def _fail(self, *_, **__):
        raise CapmapError(f"config field {self.path} is not in this stage's slice: declare it in "
                          "capmap.config.slices.STAGES (else a change of it would not rerun the stage)")

    __getattr__ = __call__ = __iter__ = __len__ = __getitem__ = __float__ = __int__ = __index__ = _fail
    __bool__ = __add__ = __radd__ = __sub__ = __rsub__ = __mul__ = __rmul__ = __truediv__ = __lt__ = __gt__ = _fail
    __le__ = __ge__ = __array__ = __eq__ = __ne__ = __hash__ = __str__ = __format__ = __fspath__ = _fail
    __neg__ = __abs__ = __pow__ = __rpow__ = __rtruediv__ = __round__ = __contains__ = __mod__ = __floordiv__ = _fail

    def __repr__(self) -> str:
        return f"<undeclared {self.path}>"


def rounded(value, meta: dict):
    """``value`` rounded as its field's ``ROUND`` metadata says (unchanged without)."""
    digits = meta.get("round")
    if digits is None or value is None:
        return value
    if isinstance(value, (list, tuple)):
        return [round(float(v), digits) for v in value]
    return round(float(value), digits)


def to_doc(obj: Any) -> Any:
    """A dataclass (every field, defaults included), tuple, array or dict as plain JSON values."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: rounded(to_doc(getattr(obj, f.name)), f.metadata) for f in dataclasses.fields(obj)}
    if isinstance(obj, dict):
        return {str(k): to_doc(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_doc(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Undeclared):
        obj._fail()
    return obj


class _Names(dict):
    """A module's names, and the types its ``SECTION_TYPES`` names (imported on first use)."""

    def __init__(self, module):
        super().__init__(vars(module))
        self.lazy = getattr(module, "SECTION_TYPES", {})

    def __missing__(self, name: str):
        if name not in self.lazy:
            raise KeyError(name)
        return getattr(importlib.import_module(self.lazy[name]), name)


@lru_cache(maxsize=None)
def _hint(cls: type, name: str):
    """The type of field ``name`` of ``cls``, resolved alone (a string annotation evaluated in its
    module's names): rebuilding a partial document imports only the types of its fields."""
    ann = cls.__dataclass_fields__[name].type
    if not isinstance(ann, str):
        return ann
    return eval(ann, {"__builtins__": builtins}, _Names(sys.modules[cls.__module__]))  # noqa: S307 (our annotations)


def _args(hint) -> tuple:
    return typing.get_args(hint)


def _is_union(hint) -> bool:
    return typing.get_origin(hint) in (typing.Union, types.UnionType)


def _convert(hint, value, path: str):
    """``value`` (JSON) as type ``hint``."""
    if value is None:
        return None
    if _is_union(hint):
        options = [a for a in _args(hint) if a is not type(None)]
        for opt in options:  # the option whose shape matches the value's
            origin = typing.get_origin(opt) or opt
            if isinstance(value, dict) and (dataclasses.is_dataclass(opt) or origin is dict):
                return _convert(opt, value, path)
            if isinstance(value, list) and origin in (tuple, list, np.ndarray):
                return _convert(opt, value, path)
            if not isinstance(value, (dict, list)) and origin in (float, int, str, bool):
                return _convert(opt, value, path)
        raise CapmapError(f"{path}: {value!r} fits none of {hint}")
    if dataclasses.is_dataclass(hint):
        return partial(hint, value, path)
    origin = typing.get_origin(hint)
    if origin is tuple:
        args = _args(hint)
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(args[0], v, f"{path}[{i}]") for i, v in enumerate(value))
        return tuple(_convert(a, v, f"{path}[{i}]") for i, (a, v) in enumerate(zip(args, value)))
    if origin is dict:
        return {k: _convert(_args(hint)[1], v, f"{path}.{k}") for k, v in value.items()}
    if hint is np.ndarray:
        return np.asarray(value, dtype=float)
    if hint is float:
        return float(value)
    if hint is int:
        if float(value) != int(value):
            raise CapmapError(f"{path} = {value!r} is not an integer")
        return int(value)
    if hint in (str, bool):
        return hint(value)
    return value


def partial(cls: type, doc: dict, path: str = "") -> Any:
    """An instance of dataclass ``cls`` from a (possibly partial) document: the fields present are
    converted by their type hints, the others are :class:`Undeclared`. Built without ``__init__``:
    the values were validated when the whole configuration was."""
    obj = object.__new__(cls)
    for f in dataclasses.fields(cls):
        where = f"{path}.{f.name}" if path else f.name
        value = _convert(_hint(cls, f.name), doc[f.name], where) if f.name in doc else Undeclared(where)
        object.__setattr__(obj, f.name, value)
    return obj


def field_meta(obj: Any, name: str) -> dict:
    """The metadata of field ``name`` of dataclass instance ``obj`` ({} when none)."""
    for f in dataclasses.fields(obj):
        if f.name == name:
            return dict(f.metadata)
    raise CapmapError(f"{type(obj).__name__} has no config field {name}")


def get_path(root: Any, path: str) -> tuple[Any, dict, str]:
    """The value at dotted ``path`` under ``root``, its field metadata, and '' — or, when a section on
    the way is None (absent from the config), (None, {}, that section's dotted path)."""
    obj, meta, parts = root, {}, path.split(".")
    for k, name in enumerate(parts):
        if obj is None:
            return None, {}, ".".join(parts[:k])
        meta = field_meta(obj, name)
        obj = getattr(obj, name)
    return obj, meta, ""


def file_paths(value: Any, meta: dict) -> list[str]:
    """The file names held by a value at a ``FILE`` field, or by ``FILE`` fields inside it."""
    if value is None:
        return []
    if meta.get("file"):
        return [str(value)]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return [p for f in dataclasses.fields(value) for p in file_paths(getattr(value, f.name), dict(f.metadata))]
    return []


def as_tuple(value):
    """Lists of a parsed document as tuples (hashable, immutable), anything else unchanged."""
    return tuple(value) if isinstance(value, list) else value


def per_item(value, n: int, key: str) -> np.ndarray:
    """One value for all n items, or exactly n values (else a one-line error naming key)."""
    v = np.atleast_1d(np.asarray(value, dtype=float))
    if len(v) == 1:
        return np.full(n, v[0])
    if len(v) != n:
        raise ConfigError(f"{key} has {len(v)} values; give one or {n}")
    return v
