"""YAML loading and JSON-schema validation with one-line errors."""

from __future__ import annotations

import json
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema
import yaml

from capmap.errors import ConfigError

__all__ = ["schema", "key_path", "validate", "load_yaml", "as_tuple"]


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


def validate(doc: Any, schema_name: str, source: str) -> None:
    """Validate ``doc`` against a packaged schema; raise one :class:`ConfigError` line on failure."""
    validator = jsonschema.Draft202012Validator(schema(schema_name))
    error = jsonschema.exceptions.best_match(validator.iter_errors(doc))
    if error is None:
        return
    where = key_path(error.absolute_path)
    if error.validator == "additionalProperties":
        extra = sorted(set(error.instance) - set(error.schema.get("properties", {})))
        raise ConfigError(f"{source}: unknown key {where + '.' if error.absolute_path else ''}{extra[0]} "
                          f"(allowed: {', '.join(sorted(error.schema.get('properties', {})))})")
    raise ConfigError(f"{source}: {where}: {error.message}")


def load_yaml(path: str | Path) -> Any:
    """Parse a YAML file; malformed YAML or a missing file is one :class:`ConfigError` line."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read ({exc.strerror})") from None
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
