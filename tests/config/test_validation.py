"""Bad files and documents at the YAML and schema level: each is one ConfigError line naming the file or key,
refused quickly (no hang, no RecursionError, no template evaluated, no traceback)."""

from __future__ import annotations

import copy
import json
import os
import re
import signal
import socket
import time
from contextlib import contextmanager

import pytest

from capmap.config.run import run_name
from capmap.config.validation import (
    MAX_DEPTH,
    MAX_FILE_BYTES,
    MAX_NODES,
    load_yaml,
    normalise_integers,
    read_regular_file,
    schema,
    validate,
)
from capmap.errors import ConfigError
from tests.scenario import ROOT


@contextmanager
def _within(seconds: float = 1.0):
    """Fail (instead of hanging) when the block blocks, and when it takes longer than ``seconds``."""
    def _hang(*_):
        raise TimeoutError("blocked")
    old = signal.signal(signal.SIGALRM, _hang)
    signal.setitimer(signal.ITIMER_REAL, 5.0)
    start = time.monotonic()
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    assert time.monotonic() - start < seconds


def _one_line(call, *expect: str) -> str:
    """The ConfigError of ``call()``: one line containing every text of ``expect``."""
    with _within(), pytest.raises(ConfigError) as info:
        call()
    msg = str(info.value)
    assert "\n" not in msg and "\r" not in msg, msg
    for text in expect:
        assert text in msg, f"{text!r} not in {msg!r}"
    return msg


def _file(tmp_path, name: str, content: str | bytes) -> str:
    path = tmp_path / name
    path.write_bytes(content if isinstance(content, bytes) else content.encode("utf-8"))
    return str(path)


def _config() -> dict:
    return load_yaml(ROOT / "config" / "config.yaml")


def _bad_doc(mutate, *expect: str, schema_name: str = "config", doc=None) -> str:
    doc = copy.deepcopy(_config() if doc is None else doc)
    mutate(doc)
    return _one_line(lambda: validate(doc, schema_name, "my.yaml"), "my.yaml", *expect)


# --- the file itself ---------------------------------------------------------------------------------------------

def test_a_fifo_is_refused_without_opening_it(tmp_path):
    os.mkfifo(tmp_path / "pipe.yaml")  # opening it for reading would block until a writer came
    _one_line(lambda: load_yaml(tmp_path / "pipe.yaml"), "pipe.yaml", "FIFO", "not a regular file")


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/null", "/dev/urandom"])
def test_a_device_is_refused(device):
    _one_line(lambda: load_yaml(device), device, "character device")


def test_a_link_to_a_device_is_refused(tmp_path):
    os.symlink("/dev/zero", tmp_path / "zero.yaml")
    _one_line(lambda: load_yaml(tmp_path / "zero.yaml"), "zero.yaml", "character device")


def test_a_directory_is_refused(tmp_path):
    (tmp_path / "dir.yaml").mkdir()
    _one_line(lambda: load_yaml(tmp_path / "dir.yaml"), "dir.yaml", "is a directory")


def test_a_socket_is_refused(tmp_path):
    with socket.socket(socket.AF_UNIX) as sock:
        sock.bind(str(tmp_path / "s.yaml"))
        _one_line(lambda: load_yaml(tmp_path / "s.yaml"), "s.yaml", "socket")


def test_a_too_big_file_is_refused_before_reading(tmp_path):
    path = tmp_path / "big.yaml"
    with open(path, "wb") as f:
        f.truncate(MAX_FILE_BYTES + 1)  # sparse: nothing is written
    _one_line(lambda: load_yaml(path), "big.yaml", "larger than 4 MiB", f"{MAX_FILE_BYTES:,} bytes")


def test_a_file_of_exactly_the_limit_is_read(tmp_path):
    path = _file(tmp_path, "edge.yaml", "a: '" + "x" * (MAX_FILE_BYTES - 8) + "'\n")
    assert os.path.getsize(path) <= MAX_FILE_BYTES
    with _within():
        assert len(load_yaml(path)["a"]) == MAX_FILE_BYTES - 8


@pytest.mark.parametrize("make, expect", [
    (lambda t: str(t / "absent.yaml"), "cannot read (no such file)"),
    (lambda t: str(t / "a\x00b.yaml"), "not a valid file name"),
    (lambda t: str(t / "new\nline.yaml"), "new\\nline.yaml"),  # the name escaped: still one line
])
def test_missing_and_odd_names(tmp_path, make, expect):
    _one_line(lambda: load_yaml(make(tmp_path)), expect)


def test_the_bounded_reader_serves_other_inputs(tmp_path):
    os.mkfifo(tmp_path / "robot.urdf")
    _one_line(lambda: read_regular_file(tmp_path / "robot.urdf"), "robot.urdf", "FIFO")
    path = _file(tmp_path, "big.urdf", b"<robot/>" * 200)
    _one_line(lambda: read_regular_file(path, limit=1024), "big.urdf", "larger than 0.0009765", "(1,024 bytes)")
    assert read_regular_file(path, limit=1600) == b"<robot/>" * 200


def test_a_symlink_loop_is_refused(tmp_path):
    os.symlink(tmp_path / "b.yaml", tmp_path / "a.yaml")
    os.symlink(tmp_path / "a.yaml", tmp_path / "b.yaml")
    _one_line(lambda: load_yaml(tmp_path / "a.yaml"), "a.yaml", "cannot read")


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads any file")
def test_an_unreadable_file_is_refused(tmp_path):
    path = _file(tmp_path, "secret.yaml", "a: 1\n")
    os.chmod(path, 0)
    _one_line(lambda: load_yaml(path), "secret.yaml", "cannot read (Permission denied)")


@pytest.mark.parametrize("content, expect", [
    (bytes(range(256)) * 4, "not a text (UTF-8) file: byte 128 is 0x80"),
    (b"a: 1\n\x00\x00b: 2\n", "contains NUL bytes"),
    (b"a: \x01\x02\n", "malformed YAML"),
    ("a: 1\n---\nb: 2\n", "expected a single document"),
    ("a: [1, 2\n", "malformed YAML at line 2"),
])
def test_binary_and_malformed_files(tmp_path, content, expect):
    _one_line(lambda: load_yaml(_file(tmp_path, "bad.yaml", content)), "bad.yaml", expect)


# --- the YAML's structure ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("text", [
    "[" * 20_000 + "]" * 20_000,  # was a RecursionError
    "{a: " * 20_000 + "1" + "}" * 20_000,
    "".join("  " * i + f"k{i}:\n" for i in range(MAX_DEPTH + 5)) + "  " * (MAX_DEPTH + 5) + "v\n",
], ids=["flow_lists_20000", "flow_maps_20000", "block_maps_69"])
def test_deep_nesting_is_refused(tmp_path, text):
    _one_line(lambda: load_yaml(_file(tmp_path, "deep.yaml", text)), "deep.yaml", f"nested deeper than {MAX_DEPTH} levels")


def test_nesting_up_to_the_limit_is_read(tmp_path):
    with _within():
        doc = load_yaml(_file(tmp_path, "ok.yaml", "[" * MAX_DEPTH + "1" + "]" * MAX_DEPTH))
    for _ in range(MAX_DEPTH):
        doc = doc[0]
    assert doc == 1


def test_an_alias_bomb_is_refused(tmp_path):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]" for i in range(1, 10)]  # 9**10 values
    _one_line(lambda: load_yaml(_file(tmp_path, "lol.yaml", "\n".join(lines))), "lol.yaml", f"more than {MAX_NODES:,} values",
              "billion laughs")


def test_aliases_that_nest_too_deep_are_refused(tmp_path):
    text = "".join(f"a{i}: &a{i} [[[[[[[[[[" + (f"*a{i - 1}" if i else "1") + "]]]]]]]]]]\n" for i in range(10))
    _one_line(lambda: load_yaml(_file(tmp_path, "chain.yaml", text)), "chain.yaml", "nested deeper than")


@pytest.mark.parametrize("text, expect", [
    ("a: &a [1, *a]\n", "alias *a at line 1 is inside its own anchor (a recursive structure)"),
    ("a: *nowhere\n", "alias *nowhere at line 1 has no anchor before it"),
])
def test_recursive_and_undefined_aliases(tmp_path, text, expect):
    _one_line(lambda: load_yaml(_file(tmp_path, "alias.yaml", text)), "alias.yaml", expect)


def test_ordinary_anchors_and_merge_keys_still_work(tmp_path):
    text = "base: &b {x: 1, y: 2}\nother: {<<: *b, y: 3}\nlist: &l [1, 2]\nagain: *l\n"
    with _within():
        doc = load_yaml(_file(tmp_path, "ok.yaml", text))
    assert doc["other"] == {"x": 1, "y": 3} and doc["again"] == [1, 2]
    assert load_yaml(ROOT / "config" / "robots" / "reconfig3.yaml")["arms"][1]["joints"][0]["name"] == "J1"


@pytest.mark.parametrize("value", ["true", "false", "1"])
def test_a_yte_template_is_refused(tmp_path, value):
    text = f"__use_yte__: {value}\nrun: ?__import__('os').system('touch {tmp_path}/pwned')\n"
    _one_line(lambda: load_yaml(_file(tmp_path, "yte.yaml", text)), "yte.yaml", "__use_yte__",
              "capmap does not evaluate YTE templates")
    assert not (tmp_path / "pwned").exists()


@pytest.mark.parametrize("text, expect", [
    # what the file holds is not echoed (a file may not be what it claims): the line and column say where
    ("a: 1\nb: 2020-02-30\n", "line 2, column 4: cannot read the value: not a valid timestamp (day is out of range"),
    ("a: " + "1" * 5000 + "\n", "cannot read the value: not a valid int"),  # Python's int digit limit: was a ValueError
    ("a: !!int xsecretx\n", "cannot read the value: not a valid int (invalid literal for int() with base 10: ...)"),
    ("a: !!timestamp x\n", "not a valid timestamp"),  # was an AttributeError
    ("a: 1\nb: 2\nab_secret: 3\nab_secret: 4\n", "line 4, column 1: a key is given twice"),  # was silently the last
    ("a: !!python/object/apply:os.system ['touch pwned']\n", "could not determine a constructor"),
])
def test_values_yaml_cannot_build(tmp_path, text, expect):
    msg = _one_line(lambda: load_yaml(_file(tmp_path, "v.yaml", text)), "v.yaml", expect)
    assert "secret" not in msg and "2020-02-30" not in msg and "1111" not in msg  # nothing the file holds


# --- the schema --------------------------------------------------------------------------------------------------

def test_the_default_config_validates_unchanged():
    doc = _config()
    assert validate(doc, "config", "config.yaml") == doc


def test_every_schema_pattern_refuses_a_trailing_newline():
    for name in ("config", "robot", "scene"):
        patterns = re.findall(r'"pattern": ("(?:[^"\\]|\\.)*")', json.dumps(schema(name)))
        for pattern in map(json.loads, patterns):  # jsonschema applies re.search, where $ matches before a final \n
            assert pattern.startswith("^") and pattern.endswith("\\Z"), (name, pattern)
            assert re.search(pattern, "ok") or re.search(pattern, "OK")
            assert not re.search(pattern, "ok\n") and not re.search(pattern, "OK\n")


@pytest.mark.parametrize("mutate, expect", [
    (lambda d: d.update(run="tinyx\n"), "run: 'tinyx\\n' does not match"),
    (lambda d: d["tasks"][0].update(name="around\n"), "tasks[0].name: 'around\\n' does not match"),
])
def test_a_trailing_newline_in_a_name_is_refused(mutate, expect):
    _bad_doc(mutate, expect)


def test_a_trailing_newline_in_a_robot_joint_name_is_refused():
    doc = load_yaml(ROOT / "config" / "robots" / "reconfig3.yaml")
    # the three arms share these joints through a YAML alias: jsonschema reports one of them
    _bad_doc(lambda d: d["arms"][0]["joints"][0].update(name="J1\n"), "].joints[0].name: 'J1\\n' does not match",
             schema_name="robot", doc=doc)


def test_integral_floats_become_ints_where_the_schema_says_integer():
    doc = _config()
    doc["sampling"]["seed"], doc["shards"], doc["lock"]["joint"] = 7.0, 2.0, 1.0
    doc["voxels"]["refine"] = {"rel_tol": 0.01, "min_points": 8.0, "max_points": 64.0}  # inside a oneOf branch
    doc["task"]["v_max_mps"] = 1.0  # a "number": stays a float
    out = validate(doc, "config", "my.yaml")
    assert out["sampling"]["seed"] == 7 and type(out["sampling"]["seed"]) is int
    assert type(out["shards"]) is int and type(out["lock"]["joint"]) is int
    assert type(out["voxels"]["refine"]["min_points"]) is int and type(out["voxels"]["refine"]["max_points"]) is int
    assert type(out["task"]["v_max_mps"]) is float and type(out["voxels"]["refine"]["rel_tol"]) is float
    assert type(doc["sampling"]["seed"]) is float  # the caller's document is not changed
    assert normalise_integers(doc, "config") == out


@pytest.mark.parametrize("mutate, expect", [
    (lambda d: d["sampling"].update(seed=7.5), "sampling.seed: 7.5 is not of type 'integer'"),
    (lambda d: d.update(shards=2.5), "shards: 2.5 is not of type 'integer'"),
    (lambda d: d["lock"].update(joint=1.5), "lock.joint: 1.5 is not of type 'integer'"),
])
def test_a_fractional_integer_is_refused(mutate, expect):
    _bad_doc(mutate, expect)


@pytest.mark.parametrize("mutate, expect", [
    (lambda d: d.update({"colour\nred": 1}), "unknown key colour\\nred"),
    (lambda d: d.update({None: 1, 3: 2}), "unknown key 3"),  # keys YAML reads as null and int: was a TypeError
    (lambda d: d.update(shards="nan"), "shards: 'nan' is not of type 'integer'"),  # not "write nan"
    (lambda d: d["task"].update(payload_kg=["x" * 100_000]), "task.payload_kg"),  # the message is cut
])
def test_odd_keys_and_values_stay_one_short_line(mutate, expect):
    assert len(_bad_doc(mutate, expect)) < 1000


def test_a_recursive_or_huge_document_is_refused_by_validate():
    loop: list = []
    loop.append(loop)  # what a loader with recursive aliases builds: was a RecursionError
    _bad_doc(lambda d: d["task"].update(q_ini_deg=loop), "task.q_ini_deg[0][0]", f"nested deeper than {MAX_DEPTH}")
    shared = [1.0] * 10
    for _ in range(6):
        shared = [shared] * 10  # 10**7 values through shared lists
    _bad_doc(lambda d: d.update(extra=shared), f"more than {MAX_NODES:,} values")


# --- run names ---------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("source", ["_.yaml", "ü.yaml", "测试.yaml", "configs/-.yaml", "a.yaml, 测试.yaml"])
def test_a_file_name_without_a_usable_run_name_is_refused(source):
    _one_line(lambda: run_name({}, source), source.split(", ")[-1], "add a line `run: <name>`")


@pytest.mark.parametrize("doc, source, name", [
    ({}, "config", "default"),  # no config file at all
    ({}, "configs/my lock.yaml", "my_lock"),
    ({}, "configs/ü1.yaml", "1"),
    ({}, "a.yaml, b/my_lock95.yaml", "my_lock95"),
    ({"run": "mine"}, "测试.yaml", "mine"),
    ({"run": "mine"}, "config", "mine"),
])
def test_run_names(doc, source, name):
    assert run_name(doc, source) == name
