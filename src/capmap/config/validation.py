"""YAML loading and JSON-schema validation with one-line errors.

:func:`load_yaml` opens only a regular file (never a FIFO, which blocks, a device such as /dev/zero, a directory or
a socket) of at most ``MAX_FILE_BYTES``, UTF-8 text without NUL bytes. It scans the YAML events (iteratively) before
building anything: nesting deeper than ``MAX_DEPTH`` or more than ``MAX_NODES`` nodes with every alias counted at
each reference (a "billion laughs" bomb) is refused. Anchors and aliases stay allowed (robot files repeat an arm's
joints with them); the count bounds what any consumer walks. A top-level ``__use_yte__`` is refused: capmap never
evaluates templates (Snakemake's YTE runs Python from a config). :func:`validate` checks a document against a
packaged schema and returns it with integral floats as ints where the schema says "integer"."""

from __future__ import annotations

import itertools
import json
import math
import os
import re
import stat
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Any

import jsonschema
import yaml

from capmap.errors import ConfigError

__all__ = ["schema", "key_path", "validate", "load_yaml", "check_finite", "normalise_integers",
           "shown", "read_regular_file", "file_kind", "too_big", "MAX_FILE_BYTES", "MAX_DEPTH", "MAX_NODES"]

MAX_FILE_BYTES = 4 * 1024 * 1024  # 4 MiB: a config, robot or scene file is a few kB
MAX_DEPTH = 64  # levels of nested mappings and lists (the schemas need fewer than 10)
MAX_NODES = 100_000  # values, each alias counted at every reference (shipped files: < 500; jsonschema: ~10 us each)
_SHOWN_CHARS = 300  # longest text (a key, a file name, a jsonschema message) put into an error line
_NOT_FILES = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
              (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


@lru_cache(maxsize=None)
def schema(name: str) -> dict:
    """The packaged JSON schema ``capmap/config/schemas/<name>.schema.json``."""
    text = resources.files("capmap.config").joinpath(f"schemas/{name}.schema.json").read_text()
    return json.loads(text)


@lru_cache(maxsize=None)
def _validator(name: str) -> jsonschema.Draft202012Validator:
    return jsonschema.Draft202012Validator(schema(name))


def shown(text: Any) -> str:
    """``text`` fit for one error line: control characters (a newline in a file name or key) escaped, cut if long."""
    text = str(text)
    if not text.isprintable():
        text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    return text if len(text) <= _SHOWN_CHARS else text[:_SHOWN_CHARS] + "..."


def key_path(parts) -> str:
    """``['links', 3, 'mass_kg']`` -> ``links[3].mass_kg`` (1-based list indices are not used)."""
    out = ""
    for p in parts:
        out += f"[{p}]" if isinstance(p, int) else (f".{shown(p)}" if out else shown(p))
    return out or "<top level>"


def _nodes(doc: Any, source: str, path: tuple = ()):
    """Every (path, value) of ``doc`` in document order, iteratively; nesting deeper than MAX_DEPTH or more than
    MAX_NODES values (shared or recursive structures walk as often as they are referenced) is a ConfigError."""
    stack, count = [(path, doc)], 0
    while stack:
        path, value = stack.pop()
        count += 1
        if count > MAX_NODES:
            raise ConfigError(f"{shown(source)}: more than {MAX_NODES:,} values (shared parts counted where used), too many")
        if len(path) > MAX_DEPTH:
            raise ConfigError(f"{shown(source)}: {key_path(path[:8])}...: nested deeper than {MAX_DEPTH} levels")
        yield path, value
        if isinstance(value, dict):
            stack.extend(reversed([(path + (k,), v) for k, v in value.items()]))
        elif isinstance(value, (list, tuple)):
            stack.extend(reversed([(path + (i,), v) for i, v in enumerate(value)]))


def check_finite(doc: Any, source: str, path: tuple = ()) -> None:
    """Every number in the document is finite (YAML's .nan and .inf are refused, naming the key); also bounds the
    document's nesting (MAX_DEPTH) and size (MAX_NODES) without recursion."""
    for where, value in _nodes(doc, source, path):
        if isinstance(value, float) and not math.isfinite(value):
            raise ConfigError(f"{shown(source)}: {key_path(where)} = {value} is not a finite number")


def _as_number(text: str) -> float | None:
    try:
        x = float(text)
    except ValueError:
        return None
    return x if math.isfinite(x) else None


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


def _key(k: Any) -> str:  # a mapping key in a message: YAML keys may be null, numbers, dates
    return shown(k) if isinstance(k, str) else repr(k)


def validate(doc: Any, schema_name: str, source: str) -> Any:
    """Validate ``doc`` against a packaged schema; raise one :class:`ConfigError` line on failure. Returns the
    document with integral floats at integer keys as ints (:func:`normalise_integers`; ``doc`` is not changed)."""
    known = schema(schema_name).get("properties", {})
    if isinstance(doc, dict) and doc and known and not any(k in known for k in doc):
        raise ConfigError(f"{shown(source)}: not a capmap {schema_name} file: none of its keys is one of a "
                          f"{schema_name} file's ({', '.join(sorted(known)[:6])}, ...)")
    check_finite(doc, source)
    error = jsonschema.exceptions.best_match(itertools.islice(_validator(schema_name).iter_errors(doc), 1000))
    if error is None:
        return normalise_integers(doc, schema_name)
    where, name = key_path(error.absolute_path), shown(source)
    if isinstance(error.instance, str) and _as_number(error.instance) is not None and \
            _admits_numbers(error.schema, schema(schema_name)):
        raise ConfigError(f"{name}: {where} = '{shown(error.instance)}' is text, not a number: YAML reads a number "
                          f"written like 1e-4 (no decimal point) as a string; write {_plain(float(error.instance))}")
    if error.validator == "additionalProperties" and isinstance(error.instance, dict):
        allowed = error.schema.get("properties", {})
        extra = sorted((k for k in error.instance if k not in allowed), key=repr)
        if extra:
            raise ConfigError(f"{name}: unknown key {where + '.' if error.absolute_path else ''}{_key(extra[0])} "
                              f"(allowed: {', '.join(sorted(allowed))})")
    raise ConfigError(f"{name}: {where}: {shown(error.message)}")


def normalise_integers(doc: Any, schema_name: str) -> Any:
    """A copy of a valid ``doc`` with every integral float (``7.0``) where the schema says "integer" turned into an
    int: jsonschema (the JSON data model) accepts 7.0 as an integer, numpy's default_rng and range() do not.
    Follows local ``$ref``, properties, additionalProperties, items/prefixItems, allOf, and the one branch of a
    oneOf/anyOf the value is valid under (several: ambiguous, not descended). Mappings and lists are copied."""
    validator = _validator(schema_name)
    return _normalised(doc, [validator.schema], validator, 0)


def _resolve(root: dict, ref: str) -> Any:
    """A local ``$ref`` ("#/$defs/vec3"), else None."""
    if not ref.startswith("#"):
        return None
    node = root
    for part in filter(None, ref[1:].split("/")):
        part = part.replace("~1", "/").replace("~0", "~")
        node = node.get(part) if isinstance(node, dict) else None
    return node


def _applicable(subs: list, value: Any, validator, depth: int = 0) -> list[dict]:
    """The subschemas ``subs`` and those they bring in ($ref, allOf, a oneOf/anyOf branch) that apply to ``value``."""
    out = []
    for sub in subs:
        if not isinstance(sub, dict) or depth > 16:
            continue
        out.append(sub)
        more = list(sub.get("allOf", []))
        if isinstance(sub.get("$ref"), str):
            more.append(_resolve(validator.schema, sub["$ref"]))
        for key in ("oneOf", "anyOf"):
            matching = [b for b in sub.get(key, []) if validator.evolve(schema=b).is_valid(value)]
            more += matching if len(matching) == 1 else []
        out += _applicable(more, value, validator, depth + 1)
    return out


def _says_integer(sub: dict) -> bool:
    types = sub.get("type") if isinstance(sub.get("type"), list) else [sub.get("type")]
    return "integer" in types and "number" not in types


def _for_key(parts: list[dict], key: Any) -> list:
    out = []
    for p in parts:
        props, patterns = p.get("properties", {}), p.get("patternProperties", {})
        matched = [s for pat, s in patterns.items() if isinstance(key, str) and re.search(pat, key)]
        out += ([props[key]] if key in props else []) + matched
        if key not in props and not matched and isinstance(p.get("additionalProperties"), dict):
            out.append(p["additionalProperties"])
    return out


def _for_index(parts: list[dict], i: int) -> list:
    out = []
    for p in parts:
        prefix = p.get("prefixItems", [])
        out += [prefix[i]] if i < len(prefix) else ([p["items"]] if isinstance(p.get("items"), dict) else [])
    return out


def _normalised(value: Any, subs: list, validator, depth: int) -> Any:
    parts = _applicable(subs, value, validator) if subs and depth <= MAX_DEPTH else []
    if isinstance(value, float) and value.is_integer() and any(_says_integer(p) for p in parts):
        return int(value)
    if isinstance(value, dict):
        return {k: _normalised(v, _for_key(parts, k), validator, depth + 1) for k, v in value.items()}
    if isinstance(value, list):
        return [_normalised(v, _for_index(parts, i), validator, depth + 1) for i, v in enumerate(value)]
    return value


def _without_quotes(exc: Exception) -> str:
    """An exception's text with what it quotes from the file left out (a file may not be what it claims)."""
    return shown(re.sub(r"'[^']*'|\"[^\"]*\"", "...", str(exc).splitlines()[0] if str(exc) else type(exc).__name__))


class _Loader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
    """The safe loader (libyaml when present). A scalar it cannot construct (``2020-02-30``, an int of 5000 digits,
    ``!!int x``) or a key repeated in one mapping is a YAML error with its line, not a traceback or a lost value."""

    def construct_object(self, node, deep=False):
        try:
            return super().construct_object(node, deep=deep)
        except (ValueError, TypeError, AttributeError, OverflowError) as exc:  # AttributeError: !!timestamp x
            kind = node.tag.rsplit(":", 1)[-1]
            why = "" if isinstance(exc, AttributeError) else f" ({_without_quotes(exc)})"
            what = "value" if isinstance(node, yaml.ScalarNode) else f"{kind} node"
            raise yaml.constructor.ConstructorError(None, None, f"cannot read the {what}: not a valid {kind}{why}",
                                                    node.start_mark) from None

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value if isinstance(node, yaml.MappingNode) else ():
            if isinstance(key_node, yaml.ScalarNode) and key_node.tag != "tag:yaml.org,2002:merge":
                key = self.construct_object(key_node)
                if key in seen:
                    raise yaml.constructor.ConstructorError(None, None, "a key is given twice in one mapping",
                                                            key_node.start_mark)
                seen.add(key)
        return super().construct_mapping(node, deep=deep)


def _check_events(text: str, name: str) -> None:
    """Scan the YAML events (no recursion, nothing built): nesting at most MAX_DEPTH (aliases expanded), at most
    MAX_NODES nodes with every alias counted at its full size each time it is referenced, no recursive alias."""
    sizes: dict[str, tuple[int, int]] = {}  # anchor -> (nodes, levels) of its node, aliases expanded
    stack: list[list] = [[0, 0, None]]  # the stream, then each open collection: [nodes, levels inside, anchor]
    total = 0
    for event in yaml.parse(text, Loader=_Loader):
        if isinstance(event, yaml.CollectionEndEvent):
            nodes, levels, anchor = stack.pop()
            sizes.update({} if anchor is None else {anchor: (nodes, levels + 1)})
            stack[-1][0], stack[-1][1] = stack[-1][0] + nodes, max(stack[-1][1], levels + 1)
            continue
        if isinstance(event, yaml.AliasEvent):
            if event.anchor not in sizes:
                own = any(s[2] == event.anchor for s in stack)
                raise ConfigError(f"{name}: alias *{shown(event.anchor)} at line {event.start_mark.line + 1} " +
                                  ("is inside its own anchor (a recursive structure)" if own else "has no anchor before it"))
            nodes, levels = sizes[event.anchor]
        elif isinstance(event, (yaml.ScalarEvent, yaml.CollectionStartEvent)):
            nodes, levels = 1, int(isinstance(event, yaml.CollectionStartEvent))
        else:
            continue
        total += nodes
        if len(stack) - 1 + levels > MAX_DEPTH:
            raise ConfigError(f"{name}: nested deeper than {MAX_DEPTH} levels at line {event.start_mark.line + 1}")
        if total > MAX_NODES:
            raise ConfigError(f"{name}: more than {MAX_NODES:,} values by line {event.start_mark.line + 1} (each alias "
                              "counted where it is used: a 'billion laughs' bomb?), too many for a capmap file")
        if isinstance(event, yaml.CollectionStartEvent):
            stack.append([1, 0, event.anchor])
            continue
        if isinstance(event, yaml.ScalarEvent) and event.anchor is not None:
            sizes[event.anchor] = (1, 0)
        stack[-1][0], stack[-1][1] = stack[-1][0] + nodes, max(stack[-1][1], levels)


def file_kind(mode: int, name: str) -> None:  # one line naming what a path is when not a regular file
    if not stat.S_ISREG(mode):
        raise ConfigError(f"{name}: is {next((k for test, k in _NOT_FILES if test(mode)), 'a special file')}, not a regular file")


def too_big(size: int, name: str, limit: int) -> None:
    if size > limit:
        raise ConfigError(f"{name}: larger than {limit / 2**20:g} MiB ({limit:,} bytes), the limit for a capmap input file")


def read_regular_file(path: str | Path, limit: int = MAX_FILE_BYTES) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes, else one ConfigError line naming it: stat first (a FIFO or
    device is never opened), then a non-blocking open, fstat again (the path may have been replaced) and a bounded read."""
    name = shown(path)
    try:
        st = os.stat(path)
        file_kind(st.st_mode, name)
        too_big(st.st_size, name, limit)
        with os.fdopen(os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)), "rb") as f:
            file_kind(os.fstat(f.fileno()).st_mode, name)
            data = f.read(limit + 1)
    except ConfigError:
        raise
    except FileNotFoundError:
        raise ConfigError(f"{name}: cannot read (no such file)") from None
    except OSError as exc:
        raise ConfigError(f"{name}: cannot read ({exc.strerror or exc})") from None
    except ValueError:  # a NUL byte in the path
        raise ConfigError(f"{name}: cannot read (not a valid file name)") from None
    too_big(len(data), name, limit)
    return data


def load_yaml(path: str | Path) -> Any:
    """Parse a YAML file; a missing, special, huge, binary, malformed, too deep, alias-bomb or YTE-template file is
    one :class:`ConfigError` line naming it (see the module docstring for the limits)."""
    path = Path(path)
    name = shown(path)
    data = read_regular_file(path)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{name}: not a text (UTF-8) file: byte {exc.start} is 0x{data[exc.start]:02x}") from None
    if "\x00" in text:
        raise ConfigError(f"{name}: not a text file (it contains NUL bytes)")
    try:
        _check_events(text, name)
        doc = yaml.load(text, Loader=_Loader)  # noqa: S506 (a safe loader)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or (str(exc).splitlines() or [type(exc).__name__])[0]
        problem = f"{exc.context}: {problem}" if getattr(exc, "context", None) else problem
        if "nesting depth" in problem:  # PyYAML >= 6.0.4's own limit (1000), met while scanning ahead of our count
            raise ConfigError(f"{name}: nested deeper than {MAX_DEPTH} levels{at}") from None
        raise ConfigError(f"{name}: malformed YAML{at}: {shown(problem)}") from None
    if isinstance(doc, dict) and "__use_yte__" in doc:
        raise ConfigError(f"{name}: __use_yte__: capmap does not evaluate YTE templates (they run Python code from a "
                          "config file); write the values out and remove __use_yte__")
    return doc

