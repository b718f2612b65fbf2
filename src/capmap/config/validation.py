"""YAML loading and JSON-schema validation with one-line errors."""

from __future__ import annotations

import json
import math
import re
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema
import numpy as np
import yaml

from capmap.errors import ConfigError

__all__ = ["schema", "key_path", "validate", "load_yaml", "as_tuple", "check_finite", "per_item"]


@lru_cache(maxsize=None)
def schema(name: str) -> dict:
    """The packaged JSON schema ``capmap/config/schemas/<name>.schema.json``."""
    text = resources.files("capmap.config").joinpath(f"schemas/{name}.schema.json").read_text()
    return json.loads(text)


def key_path(parts) -> str:
    """``['links', 3, 'mass_kg']`` -> ``links[3].mass_kg`` (1-based list indices are not used)."""
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out or "<top level>"


def check_finite(doc: Any, source: str, path: tuple = ()) -> None:
    """Every number in the document is finite (YAML's .nan and .inf are refused, naming the key)."""
    if isinstance(doc, dict):
        for k, v in doc.items():
            check_finite(v, source, path + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            check_finite(v, source, path + (i,))
    elif isinstance(doc, float) and not math.isfinite(doc):
        raise ConfigError(f"{source}: {key_path(path)} = {doc} is not a finite number")


def _as_number(text: str) -> float | None:
    try:
        return float(text)
    except ValueError:
        return None


def _plain(x: float) -> str:
    return str(int(x)) if x.is_integer() and abs(x) < 1e15 else repr(x)


def _admits_numbers(sub: dict, root: dict) -> bool:
    """Whether a (sub)schema accepts numbers somewhere (following local $refs)."""
    text = json.dumps(sub)
    for ref in re.findall(r'"\$ref": "#/([^"]+)"', text):
        node = root
        for part in ref.split("/"):
            node = node[part]
        text += json.dumps(node)
    return '"number"' in text or '"integer"' in text


def validate(doc: Any, schema_name: str, source: str) -> None:
    """Validate ``doc`` against a packaged schema; raise one :class:`ConfigError` line on failure."""
    check_finite(doc, source)
    validator = jsonschema.Draft202012Validator(schema(schema_name))
    error = jsonschema.exceptions.best_match(validator.iter_errors(doc))
    if error is None:
        return
    where = key_path(error.absolute_path)
    if isinstance(error.instance, str) and _as_number(error.instance) is not None and \
            _admits_numbers(error.schema, schema(schema_name)):
        raise ConfigError(f"{source}: {where} = '{error.instance}' is text, not a number: YAML reads a number "
                          f"written like 1e-4 (no decimal point) as a string; write {_plain(float(error.instance))}")
    if error.validator == "additionalProperties":
        extra = sorted(set(error.instance) - set(error.schema.get("properties", {})))
        raise ConfigError(f"{source}: unknown key {where + '.' if error.absolute_path else ''}{extra[0]} "
                          f"(allowed: {', '.join(sorted(error.schema.get('properties', {})))})")
    raise ConfigError(f"{source}: {where}: {error.message}")


def load_yaml(path: str | Path) -> Any:
    """Parse a YAML file; malformed YAML or a missing file is one :class:`ConfigError` line."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read ({exc.strerror})") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{path}: not a text (UTF-8) file: byte {exc.start} is 0x{exc.object[exc.start]:02x}") from None
    if "\x00" in text:
        raise ConfigError(f"{path}: not a text file (it contains NUL bytes)")
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ConfigError(f"{path}: malformed YAML{at}: {problem}") from None


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
