"""The compiled kernels' marker: keyed by the robot file's content (not the checkout's path), and a shared
cache folder of other sources removed only once no run has used it for UNUSED_DAYS."""

import os
import time

from capmap.io import kernel_marker


def test_the_key_is_the_same_in_another_checkout(tmp_path):
    a, b = tmp_path / "one" / "ssrms7.yaml", tmp_path / "two" / "ssrms7.yaml"
    for f in (a, b):
        f.parent.mkdir()
        f.write_text("name: arm\n")
    assert kernel_marker.run_key(str(a), 1, 1.0, False) == kernel_marker.run_key(str(b), 1, 1.0, False)
    b.write_text("name: other arm\n")
    assert kernel_marker.run_key(str(a), 1, 1.0, False) != kernel_marker.run_key(str(b), 1, 1.0, False)


def test_record_prunes_only_unused_shared_folders(tmp_path, monkeypatch):
    base = tmp_path / "cache"
    mine = base / "numba-0000000000000001"
    old, recent = base / "numba-0000000000000002", base / "numba-0000000000000003"
    for d in (mine, old, recent):
        d.mkdir(parents=True)
        (d / "kernels-x.ok").write_text("")
    month = time.time() - (kernel_marker.UNUSED_DAYS + 1) * 86400
    os.utime(old / "kernels-x.ok", (month, month))
    monkeypatch.setattr(kernel_marker.numba_config, "CACHE_DIR", str(mine))
    kernel_marker.record("a run")
    assert mine.is_dir() and recent.is_dir() and not old.exists()
    assert kernel_marker.is_warm("a run") and not kernel_marker.is_warm("another run")
