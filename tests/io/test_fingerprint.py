"""Code fingerprints follow what a job runs, including names a package face resolves lazily."""

import textwrap

import pytest

from capmap.io import fingerprint as fp
from tests.scenario import ROOT

_CACHED = (fp.module_closure, fp._module_tree, fp._module_imports, fp._module_digest, fp._lazy_exports,
           fp.code_fingerprint, fp._script_fingerprint, fp._source_hash, fp._disk)


@pytest.fixture
def fresh(monkeypatch):
    """Empty the per-process caches before and after (a test changes the tree or the digests), and no
    disk cache (a test that patches a digest would otherwise read the fingerprint an earlier process left)."""
    for f in _CACHED:
        f.cache_clear()
    monkeypatch.setattr(fp, "_disk", lambda: {})
    monkeypatch.setattr(fp, "_remember", lambda key, value: None)
    yield
    for f in _CACHED:
        f.cache_clear()


def _tree(root, files: dict[str, str]) -> None:
    for rel, text in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text))


@pytest.fixture
def fake(tmp_path, monkeypatch, fresh):
    """A throwaway ``capmap`` tree: a lazy face ``pkg`` (exports f from a, g from b, sub a subpackage),
    a face ``dyn`` whose exports are not a literal, a plain package, and modules importing them."""
    root = tmp_path / "capmap"
    lazy = "from capmap._lazy import lazy_exports\n__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)\n"
    _tree(root, {
        "__init__.py": "",
        "_lazy.py": "def lazy_exports(p, e):\n    return None, None\n",
        "pkg/__init__.py": "_EXPORTS = {'f': 'a', 'g': 'b', 'sub': 'sub'}\n" + lazy,
        "pkg/a.py": '"""Defines f."""\ndef f():\n    return 1\n',
        "pkg/b.py": "def g():\n    return 2\n",
        "pkg/sub/__init__.py": "",
        "dyn/__init__.py": "_EXPORTS = dict(f='a')\n" + lazy,
        "dyn/a.py": "def f():\n    return 1\n",
        "dyn/deep/__init__.py": "",
        "plain/__init__.py": "X = 1\n",
        "plain/c.py": "Y = 2\n",
        "uses_f.py": "from capmap.pkg import f\n",
        "uses_star.py": "from capmap.pkg import *\n",
        "uses_module.py": "import capmap.pkg as p\n",
        "uses_from_module.py": "from capmap import pkg\n",
        "uses_submodule.py": "import capmap.pkg.b\n",
        "uses_dyn.py": "from capmap.dyn import f\n",
        "uses_plain.py": "from capmap.plain import X\n",
        "pkg/rel.py": "from . import f\n",
    })
    monkeypatch.setattr(fp, "_SRC", root)
    return root


def test_names_from_a_package_face_follow_its_exports(fake):
    assert fp.module_closure("capmap.uses_f") == ("capmap", "capmap._lazy", "capmap.pkg", "capmap.pkg.a", "capmap.uses_f")
    assert "capmap.pkg.a" in fp.module_closure("capmap.pkg.rel")
    assert "capmap.pkg.b" not in fp.module_closure("capmap.pkg.rel")


def test_a_package_face_as_a_module_counts_every_export(fake):
    every = {"capmap.pkg.a", "capmap.pkg.b", "capmap.pkg.sub"}
    for name in ("capmap.uses_star", "capmap.uses_module", "capmap.uses_from_module"):
        assert every <= set(fp.module_closure(name)), name
    # the parent of a dotted import counts with its own code only
    assert set(fp.module_closure("capmap.uses_submodule")) & every == {"capmap.pkg.b"}


def test_unreadable_exports_count_every_submodule_and_plain_packages_none(fake):
    assert {"capmap.dyn.a", "capmap.dyn.deep"} <= set(fp.module_closure("capmap.uses_dyn"))
    assert fp.module_closure("capmap.uses_plain") == ("capmap", "capmap.plain", "capmap.uses_plain")


def test_an_exported_module_s_code_changes_the_fingerprint(fake):
    before = fp.code_fingerprint("capmap.uses_f")
    (fake / "pkg/b.py").write_text("def g():\n    return 3\n")  # not used
    (fake / "pkg/a.py").write_text('"""Reworded."""\ndef f():\n    return 1\n')  # a docstring only
    for f in _CACHED:
        f.cache_clear()
    assert fp.code_fingerprint("capmap.uses_f") == before
    (fake / "pkg/a.py").write_text("def f():\n    return 2\n")
    for f in _CACHED:
        f.cache_clear()
    assert fp.code_fingerprint("capmap.uses_f") != before


def test_a_script_importing_through_the_capacity_face_follows_the_engine(tmp_path, monkeypatch, fresh):
    script = tmp_path / "job.py"
    script.write_text("from capmap.capacity import point_capacity\n\npoint_capacity\n")
    assert "capmap.capacity.engine" in fp.module_closure("capmap.capacity.engine")  # sanity: a module
    assert "capmap.capacity.problem" in fp._imports("__main__", fp._tree(script))  # where the face points
    before = fp.script_fingerprint(script)
    digest = fp._module_digest

    def changed(which):
        monkeypatch.setattr(fp, "_module_digest", lambda mod: b"edited" if mod == which else digest(mod))
        fp.code_fingerprint.cache_clear()
        fp._script_fingerprint.cache_clear()
        return fp.script_fingerprint(script)

    assert changed("capmap.capacity.planning") == before  # named by the face, not imported
    assert changed("capmap.capacity.problem") != before
    assert changed("capmap.capacity.engine") != before  # imported by the problem module


def test_imports_for_annotations_only_are_not_followed_and_named_modules_are(fresh):
    """``if TYPE_CHECKING:`` imports never run: the run config's module does not depend on every
    family through them; the sections a job rebuilds are added by name (``also``)."""
    closure = fp.module_closure("capmap.config.run")
    assert "capmap.config.run" in closure and "capmap.config.jobs" in closure
    assert not {"capmap.config.dualarm", "capmap.dualarm.scene.robot", "capmap.capacity.engine"} & set(closure)
    script = ROOT / "workflow" / "scripts" / "dualarm_scan.py"
    plain = fp.script_fingerprint(script)
    assert fp.script_fingerprint(script, ["capmap.config.reconfig"]) != plain
    assert fp.script_fingerprint(script, []) == plain


def test_the_disk_cache_serves_the_same_sources_and_not_edited_ones(tmp_path, monkeypatch):
    """A second process (caches emptied) reads the fingerprints of the same sources from the disk cache
    (a wrong value planted there is what it returns); an edit of any source file is a new key."""
    for f in _CACHED:
        f.cache_clear()
    root = tmp_path / "capmap"
    _tree(root, {"__init__.py": "", "a.py": "X = 1\n", "b.py": "from capmap.a import X\n"})
    monkeypatch.setattr(fp, "_SRC", root)
    try:
        first = fp.code_fingerprint("capmap.b")
        files = list((root / "__pycache__").glob("fingerprints-*.json"))
        assert len(files) == 1 and first in files[0].read_text()
        files[0].write_text(files[0].read_text().replace(first, "planted"))
        for f in _CACHED:
            f.cache_clear()
        assert fp.code_fingerprint("capmap.b") == "planted"  # read from disk, not recomputed
        (root / "a.py").write_text("X = 2\n")
        for f in _CACHED:
            f.cache_clear()
        edited = fp.code_fingerprint("capmap.b")
        assert edited not in ("planted", first)
        assert len(list((root / "__pycache__").glob("fingerprints-*.json"))) == 1  # the old one removed
    finally:
        for f in _CACHED:
            f.cache_clear()


def test_numba_cache_folder_follows_every_compiled_source_and_only_those(tmp_path):
    """Numba checks a cached function against its own file only: an edit of a callee in another file must
    move the whole cache (capmap.numba_folder), an edit elsewhere must not."""
    from pathlib import Path

    import numba

    import capmap
    from capmap import numba_folder

    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "caller.py").write_text("import numba\nfrom pkg.sub.callee import f\n")
    (pkg / "sub" / "callee.py").write_text("import numba\n\n@numba.njit(cache=True)\ndef f(x):\n    return x\n")
    (pkg / "plain.py").write_text("X = 1\n")
    first = numba_folder(pkg, "/base")
    (pkg / "plain.py").write_text("X = 2\n")
    assert numba_folder(pkg, "/base") == first
    (pkg / "sub" / "callee.py").write_text("import numba\n\n@numba.njit(cache=True)\ndef f(x):\n    return 2 * x\n")
    assert numba_folder(pkg, "/base") != first and numba_folder(pkg, "/base").startswith("/base/numba-")
    # and capmap's own kernels use the folder of its sources
    assert numba.config.CACHE_DIR == numba_folder(Path(capmap.__file__).parent, Path(numba.config.CACHE_DIR).parent)


HEALTHY_SEARCH = {"capmap.capacity.baseline", "capmap.capacity.angle_search", "capmap.capacity.self_motion",
                  "capmap.capacity.healthy_map", "capmap.capacity.healthy_evaluator", "capmap.capacity.build_healthy"}


def test_the_maps_stages_do_not_run_the_healthy_arms_search():
    """A change in the healthy arm's search reruns the baseline, not the map: no script of the map's rules
    (model .. summary, plans, verification) imports a module of that search, directly or through others;
    the baseline's scripts do (so the test sees the search where it is)."""
    scripts = ROOT / "workflow" / "scripts"
    for name in ("model", "sample", "capacity", "points", "voxels", "refine", "voxel_map", "plan", "verify",
                 "verify_plots", "summary", "capacity_3d"):
        mods = fp.script_modules(scripts / f"{name}.py")
        closure = set().union(*(fp.module_closure(m) for m in mods))
        assert not closure & HEALTHY_SEARCH, (name, sorted(closure & HEALTHY_SEARCH))
    mods = fp.script_modules(scripts / "baseline_shard.py")
    assert HEALTHY_SEARCH <= set().union(*(fp.module_closure(m) for m in mods))
