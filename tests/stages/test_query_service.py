"""The warm process that answers ``capmap query``: its answer is the one a process of its own gives, a
changed config is read afresh, and it stops when idle."""

import json
import os
import subprocess
import sys
import time

import pytest

from tests.scenario import ROOT


def _query(env, cfg, *args):
    res = subprocess.run([sys.executable, "-m", "capmap", "query", "point", "0.379", "4.8432", "1.8878", *args,
                          "--configfile", str(cfg), "--json"], capture_output=True, text=True, env=env, cwd=ROOT,
                         timeout=600)
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout)


@pytest.fixture
def served(tmp_path):
    """A server of its own (its socket in tmp_path), ending 10 s after its last question."""
    yield {**os.environ, "CAPMAP_QUERY_SERVER": "1", "CAPMAP_QUERY_DIR": str(tmp_path), "CAPMAP_QUERY_IDLE_S": "10"}


def _wait_for_socket(folder, timeout_s=120):
    t0 = time.monotonic()
    while not list(folder.glob("query-*.sock")):
        assert time.monotonic() - t0 < timeout_s, "no query server started"
        time.sleep(0.2)


def test_a_served_answer_is_a_fresh_process_s_and_reads_an_edited_config(served, tmp_path):
    from capmap.stages import query_client

    cfg = tmp_path / "tiny.yaml"
    cfg.write_text((ROOT / "tests/data/tiny.yaml").read_text())
    alone = {**os.environ, "CAPMAP_QUERY_SERVER": "0"}
    first = _query(served, cfg, "--payload", "1500")  # answered by its own process, which starts the server
    _wait_for_socket(tmp_path)
    sock = next(tmp_path.glob("query-*.sock"))
    rc, out, err = query_client.ask({"what": "point", "point_m": [0.379, 4.8432, 1.8878], "payload_kg": 1500.0,
                                     "configfile": str(cfg), "json": True, "joints": False}, path=sock)
    assert rc == 0 and json.loads(out) == first == _query(alone, cfg, "--payload", "1500")
    # the config edited under the server: its next answer is a fresh process's on the new config
    cfg.write_text(cfg.read_text().replace("base_moment_nm: 500}", "base_moment_nm: 400}"))
    edited = _query(served, cfg, "--payload", "1500")
    assert edited == _query(alone, cfg, "--payload", "1500")
    assert edited["branches"][0]["capacity_kg"] != first["branches"][0]["capacity_kg"]


def test_the_server_ends_when_idle(tmp_path):
    env = {**os.environ, "CAPMAP_QUERY_SERVER": "1", "CAPMAP_QUERY_DIR": str(tmp_path), "CAPMAP_QUERY_IDLE_S": "2"}
    _query(env, ROOT / "tests/data/tiny.yaml")
    _wait_for_socket(tmp_path)
    t0 = time.monotonic()
    while list(tmp_path.glob("query-*.sock")):  # it removes its socket as it ends
        assert time.monotonic() - t0 < 60, "the idle server did not end"
        time.sleep(0.2)
