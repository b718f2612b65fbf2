"""Bad input never costs a good output: a table of bad configs, robot and cloud files. Each must give
exactly one line starting ``capmap:`` that names the key or file, before any job runs: every case
through the checks the workflow runs before building its DAG (in this process), and a case of each
kind as ``snakemake all`` over a finished tiny run (status 1, one stderr line, every file under
results/ byte-identical; those run in parallel: each only parses the workflow)."""

from __future__ import annotations

import hashlib
import math
import os
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest
import yaml

from capmap.checks import check_run_config
from capmap.config.run import run_document
from capmap.errors import CapmapError
from tests.scenario import ROOT, SSRMS_YAML
from tests.workflow.runs import config_file

NAN, INF = math.nan, math.inf

_TASK = {"name": "t", "start_m": [0.379, 4.8432, 1.8878], "goal_m": [2.625, 1.875, 4.875], "payload_kg": 100,
         "q_start_deg": [100, 0, 0, 0, 0, 0, 0]}

ONE_VIEW = [[0, 0, 1]]  # a user cloud's viewpoints

CONFIG_CASES = [
    ({"limts": 3}, "unknown key limts"),
    ({"tasks": [{**_TASK, "start_m": [30, 0, 0]}]}, "tasks[0] (t).start_m = [30, 0, 0] is not reachable"),
    ({"tasks": [{**_TASK, "q_start_deg": [90, 0, 0]}]}, "tasks[0] (t).q_start_deg has 3 values but"),
    ({"tasks": [{**_TASK, "name": "Bad Name"}]}, "tasks"),
    ({"tasks": [{**_TASK, "q_start_deg": [100, 124, 98, 130, 146, 174, 57], "goal_m": [30, 0, 0]}]},
     "tasks[0] (t).goal_m = [30, 0, 0] is not reachable"),
    ({"voxels.refine": {"min_points": 300}}, "voxels.refine: min_points = 300"),
    ({"planning.moves": "diagonal"}, "planning.moves"),
    ({"lock.joint": 9}, "lock.joint = 9 is out of range"),
    ({"limits.joint_torque_nm": -5}, "limits.joint_torque_nm"),
    ({"limits.joint_torque_nm": [700, 700]}, "limits.joint_torque_nm has 2 values"),
    ({"directions.n": 0}, "directions.n"),
    ({"lock.angle_deg": 400}, "lock.angle_deg = 400 is outside joint 1's range"),
    ({"lock.joint": 2, "lock.angle_deg": None, "task.q_ini_deg": [100, 280, 98, 130, 146, 174, 57]},
     "task.q_ini_deg[1] = 280 is outside"),
    ({"task.q_ini_deg": [100, 124, 98]}, "task.q_ini_deg has 3 values but ssrms7 has 7 joints"),
    ({"task.goal_m": [30, 0, 0]}, "task.goal_m = [30, 0, 0] is not reachable"),
    ({"lock.joint": 4, "lock.angle_deg": 40}, "task.start_m [0.379, 4.843, 1.888] m is not reachable at "
                                                "task.orientation_rpy_deg = [90, 0, 90] with joint 4 locked at 40 deg"),
    ({"task.payload_kg": [1500, 1500]}, "task.payload_kg"),
    ({"verification.dt_s": 0}, "verification.dt_s"),
    ({"follow.space.payload_kg": 1234}, "follow.space.payload_kg = 1234 is not one of task.payload_kg"),
    ({"follow.ground.joint_torque_nm": [14, 150]}, "follow.ground.joint_torque_nm has 2 values; give one or 6"),
    ({"follow.ground.q_start_deg": [0, 0]}, "follow.ground.q_start_deg has 2 values"),
    ({"follow.ground.speed": 1}, "unknown key"),
    ({"follow.ground.line_m": [0, 3, 0]}, "follow.ground.line_m = [0, 3, 0] ends at"),
    ({"reconfig.unlock": "arm1.J3"}, "arm1.J3 is a revolute joint, not a passive one"),
    ({"reconfig.unlock": "arm3.P1"}, "arm3.P1 is not on the closed chain through capture arm1_arm2"),
    ({"reconfig.capture": "arm1_arm9"}, "reconfig.capture = 'arm1_arm9': reconfig3 has no capture 'arm1_arm9'"),
    ({"reconfig.law.d_m": 2.0}, "reconfig.law takes arm1.P1's d to 2 m, outside its range [-0.5, 0.8] m"),
    ({"reconfig.configuration_deg.arm2": [0, 0, 0, 0, 0]}, "reconfig.configuration_deg.arm2 has 5 values but arm2 has 6"),
    ({"reconfig.configuration_deg.arm1": [0, 0, 0, 0, 0, 0]}, "reconfig.configuration_deg does not close capture"),
    ({"reconfig.joint_rate_limit_deg_s": [1, 2]}, "reconfig.joint_rate_limit_deg_s has 2 values; give one or 10"),
    ({"dualarm.horizon.pre_insertion_node": 100}, "dualarm.horizon.pre_insertion_node = 100 must lie between 0 and"),
    ({"dualarm.cloud.file": "scan.csv"}, "dualarm.cloud: give either file (and the viewpoints_m"),
    ({"dualarm.cloud": {"file": "scan.csv"}}, "dualarm.cloud.viewpoints_m is required with dualarm.cloud.file"),
    ({"dualarm.unknown.work_volume_m.x_m": [1.0, 0.0]}, "dualarm.unknown.work_volume_m"),
    ({"dualarm.unknown.voxel_m": 1e-4}, "dualarm.unknown.voxel_m: a carving grid"),
    ({"dualarm.weights.mass": 1}, "unknown key"),
    ({"dualarm.scene": "nowhere.yaml"}, "nowhere.yaml"),
    # numbers that are not numbers
    ({"task.v_max_mps": NAN}, "task.v_max_mps = nan is not a finite number"),
    ({"task.a_max_mps2": INF}, "task.a_max_mps2 = inf is not a finite number"),
    ({"task.payload_kg": [1500, NAN]}, "task.payload_kg[1] = nan is not a finite number"),
    ({"task.payload_kg": 1e300}, "task.payload_kg"),
    ({"limits.joint_torque_nm": INF}, "limits.joint_torque_nm = inf is not a finite number"),
    ({"limits.base_force_n": [200, NAN, 200]}, "limits.base_force_n[1] = nan"),
    ({"limits.base_moment_nm": -INF}, "limits.base_moment_nm = -inf"),
    ({"task.orientation_rpy_deg": [90, NAN, 90]}, "task.orientation_rpy_deg[1] = nan"),
    ({"task.start_m": [NAN, 4.8, 1.9]}, "task.start_m[0] = nan"),
    ({"task.goal_m": [2.6, INF, 4.9]}, "task.goal_m[1] = inf"),
    ({"task.q_ini_deg": [100, 124, NAN, 130, 146, 174, 57]}, "task.q_ini_deg[2] = nan"),
    ({"lock.angle_deg": NAN}, "lock.angle_deg = nan"),
    ({"voxels.edge_m": NAN}, "voxels.edge_m = nan"),
    ({"follow.period_s": INF}, "follow.period_s = inf"),
    ({"follow.space.j_max_mps3": NAN}, "follow.space.j_max_mps3 = nan"),
    ({"follow.ground.v_max_mps": INF}, "follow.ground.v_max_mps = inf"),
    ({"reconfig.dt_s": NAN}, "reconfig.dt_s = nan"),
    ({"dualarm.margin_m": INF}, "dualarm.margin_m = inf"),
    ({"atlas.edge_m": NAN}, "atlas.edge_m = nan"),
    # numbers typed as text
    ({"task.v_max_mps": "1e-1"}, "task.v_max_mps = '1e-1' is text, not a number"),
    ({"limits.base_force_n": "2e2"}, "limits.base_force_n = '2e2' is text, not a number"),
    # impossible or unaffordable sizes, verdicts from under-sampling
    ({"verification.dt_s": 5}, "verification.dt_s = 5 s is too coarse"),
    ({"voxels.edge_m": 0.05}, "voxels.edge_m: this map needs"),
    ({"sampling.n_points": 100_000_000}, "sampling.n_points = 100,000,000 joint samples"),
    ({"atlas.edge_m": 0.02}, "atlas.edge_m: this map needs"),
    ({"atlas.joints": [1, 9]}, "atlas.joints: joint 9 is out of range"),
    ({"atlas.angles_deg": [0, 400]}, "atlas.angles_deg: 400 is outside joint 1's range"),
    ({"atlas.directions.kind": "sphere", "atlas.directions.n": None}, "atlas.directions.n is required"),
    ({"advice.joints": [1, 9]}, "advice.joints: joint 9 is out of range"),
    ({"advice.step_deg": NAN}, "advice.step_deg = nan"),
    ({"advice.step_deg": 0}, "advice.step_deg"),
    ({"advice.speed": 1}, "advice"),
    ({"voxels.edge_m": -1}, "voxels.edge_m"),
    ({"shards": 0}, "shards"),
    ({"sampling.seed": -1}, "sampling.seed"),
    ({"task.payload_kg": -5}, "task.payload_kg"),
    ({"limits.base_moment_nm": [500, 500]}, "limits.base_moment_nm has 2 values"),
]

_START = [0.379, 4.8432, 1.8878]
_Q = [100, 124, 98, 130, 146, 174, 57]
# issue 23: checks moved before any job, sizes blaming the key that drives them, names and templates
NEW_CONFIG_CASES = [
    ({"verification.dt_s": 1e-9}, "verification.dt_s: verifying the task's motions at verification.dt_s = 1e-09 s"),
    ({"task.goal_m": _START}, "task.goal_m = [0.379, 4.8432, 1.8878] is the start (task.start_m): nothing to plan"),
    ({"tasks": [{**_TASK, "goal_m": _TASK["start_m"]}]}, "tasks[0] (t).goal_m equals tasks[0] (t).start_m"),
    ({"sampling.n_points": 1}, "lies outside the map's grid"),
    ({"sampling.jitter_per_voxel": 1_000_000_000}, "sampling.jitter_per_voxel: this map needs"),
    ({"directions.n": 1_000_000}, "directions.n: this map needs"),
    ({"directions.kind": "paper_grid", "directions.n": None, "directions.step_deg": 0.01},
     "directions.step_deg = 0.01 gives 1.3e+09 directions to build"),
    ({"directions.n": 5_000_000}, "directions.n = 5e+06 gives 5e+06 directions to build"),
    ({"follow.ground.line_m": [0, 1e-12, 0]}, "follow.ground.line_m = [0, 1e-12, 0] is 1e-12 m long"),
    ({"follow.period_s": 1e-9}, "follow.period_s: following"),
    ({"follow.store_period_s": 1e-4}, "follow.store_period_s = 0.0001 s is shorter than follow.period_s = 0.005 s"),
    ({"follow.store_period_s": NAN}, "follow.store_period_s = nan"),
    ({"follow.ground.v_max_mps": 1e-9}, "follow.ground.v_max_mps, follow.ground.a_max_mps2: follow.ground.line_m would take"),
    ({"task.v_max_mps": 1e-6, "task.a_max_mps2": 1e-6, "verification.dt_s": 0.05},
     "task.v_max_mps, task.a_max_mps2: the task's straight lines would take"),
    ({"reconfig.dt_s": 1e-9}, "reconfig.dt_s: the reconfiguration"),
    ({"dualarm.horizon.nodes": 10_000_000}, "dualarm.horizon.nodes: an optimal control problem of 10,000,000 nodes"),
    ({"dualarm.check.nodes": 10_000_000}, "dualarm.check.nodes: an optimal control problem"),
    ({"dualarm.fine_factor": 1_000_000}, "dualarm.fine_factor: the re-check"),
    ({"dualarm.cloud.spacing_m": 1e-5}, "dualarm.cloud.spacing_m: a synthetic scan"),
    ({"dualarm.cloud": {"file": "missing.csv", "viewpoints_m": ONE_VIEW}}, "dualarm.cloud.file = missing.csv: no such file"),
    ({"dualarm.cloud": {"file": "/etc/shadow", "viewpoints_m": ONE_VIEW}}, "dualarm.cloud.file = /etc/shadow: not a cloud file"),
    ({"dualarm.cloud": {"file": "/dev/null.csv", "viewpoints_m": ONE_VIEW}}, "dualarm.cloud.file = /dev/null.csv: no such file"),
    ({"dualarm.scene": "/dev/zero"}, "/dev/zero: is a character device"),
    ({"robot": "/dev/zero"}, "/dev/zero: is a character device"),
    ({"follow.ground.robot": "/etc"}, "/etc: is a directory"),
    ({"run": "tinyx\n"}, "run"),
    ({"tasks": [{**_TASK, "name": "t\n"}]}, "tasks[0].name"),
    ({"shards": 2.5}, "shards: 2.5 is not of type 'integer'"),
    ({"sampling.seed": 7.5}, "sampling.seed: 7.5 is not of type 'integer'"),
    ({"__use_yte__": True}, "__use_yte__: capmap does not evaluate YTE templates"),
    ({"atlas.sampling.jitter_per_voxel": 1_000_000_000}, "atlas.sampling.jitter_per_voxel: this map needs"),
    ({"tasks": [{**_TASK, "q_start_deg": _Q, "start_m": [90, 0, 0]}]}, "tasks[0] (t).start_m"),
]


def _cloud(tmp: Path, name: str, data: bytes | None = None, fifo: bool = False, folder: bool = False) -> str:
    path = tmp / name
    if fifo:
        os.mkfifo(path)
    elif folder:
        path.mkdir()
    else:
        path.write_bytes(data)
    return str(path)


CLOUD_CASES = [  # (file maker, expected text); every case names dualarm.cloud.file
    (lambda t: _cloud(t, "nocols.csv", b"a,b,c\n1,2,3\n"), "no column x_m"),
    (lambda t: _cloud(t, "binary.csv", bytes(range(128, 256)) * 8), "not a text (UTF-8) CSV file"),
    (lambda t: _cloud(t, "nul.csv", b"x_m,y_m\x00,z_m\n"), "contains NUL bytes"),
    (lambda t: _cloud(t, "fifo.csv", fifo=True), "not a regular file"),
    (lambda t: _cloud(t, "folder.csv", folder=True), "not a regular file"),
    (lambda t: _cloud(t, "garbage.parquet", b"PAR1 not really"), "not a Parquet file"),
    (lambda t: _cloud(t, "points.txt", b"x_m,y_m,z_m\n0,0,0\n"), "not a cloud file"),
    (lambda t: _cloud(t, "spaced.csv", b"x_m, y_m, z_m\n0,0,0\n"), "no column y_m"),  # as pandas would name them
]


def _robot_doc():
    return yaml.safe_load(SSRMS_YAML.read_text())


def _robot(tmp: Path, name: str, edit=None, text: str | None = None, data: bytes | None = None) -> str:
    path = tmp / name
    if data is not None:
        path.write_bytes(data)
    elif text is not None:
        path.write_text(text)
    else:
        doc = _robot_doc()
        edit(doc)
        path.write_text(yaml.safe_dump(doc))
    return str(path)


def _urdf_robot(tmp: Path, name: str, urdf_text: str) -> str:
    (tmp / f"{name}.urdf").write_text(urdf_text)
    doc = {"name": name, "urdf": {"path": f"{name}.urdf", "ee_frame": "tool0"}}
    (tmp / f"{name}.yaml").write_text(yaml.safe_dump(doc))
    return str(tmp / f"{name}.yaml")


def _set(path, value):
    def edit(doc):
        node = doc
        for k in path[:-1]:
            node = node[k]
        node[path[-1]] = value
    return edit


ROBOT_CASES = [  # (file maker, expected text in the one line); the file's name is checked too
    (lambda t: _robot(t, "binary.yaml", data=bytes(range(256)) * 4), "not a text"),
    (lambda t: _robot(t, "latin1.yaml", data="name: r\u00f6bot\n".encode("latin-1")), "not a text (UTF-8) file"),
    (lambda t: _robot(t, "empty.yaml", text=""), "a robot file must be a mapping"),
    (lambda t: _robot(t, "malformed.yaml", text="name: [a, b\ndh: {"), "malformed YAML"),
    (lambda t: _robot(t, "nan_dh.yaml", _set(["dh", "rows", 2, 1], NAN)), "dh.rows[2][1] = nan is not a finite number"),
    (lambda t: _robot(t, "inf_mass.yaml", _set(["links", 0, "mass_kg"], INF)), "links[0].mass_kg = inf"),
    (lambda t: _robot(t, "nan_com.yaml", _set(["links", 3, "com_m"], [0, NAN, 0])), "links[3].com_m[1] = nan"),
    (lambda t: _robot(t, "nan_gravity.yaml", _set(["gravity_mps2"], [0, 0, NAN])), "gravity_mps2[2] = nan"),
    (lambda t: _robot(t, "inf_base.yaml", _set(["base_com_m"], [INF, 0, 0])), "base_com_m[0] = inf"),
    (lambda t: _robot(t, "nan_tool.yaml", _set(["tool", "rpy_deg"], [0, NAN, 0])), "tool.rpy_deg[1] = nan"),
    (lambda t: _robot(t, "nan_range.yaml", _set(["joint_range_deg", 0], [NAN, 180])), "joint_range_deg[0][0] = nan"),
    (lambda t: _robot(t, "text_dh.yaml", _set(["dh", "rows", 1, 3], "5e-1")), "is text, not a number"),
    (lambda t: _robot(t, "short_row.yaml", _set(["dh", "rows", 0], [0, 0, 0])), "dh.rows[0]"),
    (lambda t: _robot(t, "inverted.yaml", _set(["joint_range_deg", 2], [90, -90])), "lower must be < upper"),
    (lambda t: _robot(t, "neg_mass.yaml", _set(["links", 1, "mass_kg"], -3)), "links[1].mass_kg"),
    (lambda t: _robot(t, "not_pd.yaml", _set(["links", 2, "inertia_kgm2"], [1, 1, -1])), "links[2].inertia_kgm2"),
    (lambda t: _robot(t, "unknown_key.yaml", _set(["colour"], "red")), "unknown key colour"),
    (lambda t: _robot(t, "few_links.yaml", lambda d: d["links"].pop()), "links has 6 entries but dh.rows has 7"),
    (lambda t: str(t / "missing.yaml"), "cannot read"),
    (lambda t: _urdf_robot(t, "garbage", "<robot><link name='a'></robot"), "not valid XML"),
    (lambda t: _urdf_robot(t, "notrobot", "<html><body/></html>"), "not a URDF"),
    (lambda t: _urdf_robot(t, "binaryurdf", "\x00\x01garbage"), "not valid XML"),
]

NEW_ROBOT_CASES = [  # issue 23: special, huge, deep, aliased, templated, duplicated files; URDFs that are not files
    (lambda t: _robot(t, "yte.yaml", _set(["__use_yte__"], True)), "capmap does not evaluate YTE templates"),
    (lambda t: _robot(t, "deep.yaml", text="a: " + "[" * 20000 + "]" * 20000 + "\n"), "nested deeper than 64 levels"),
    (lambda t: _robot(t, "bomb.yaml", text=_BOMB), "more than 100,000 values"),
    (lambda t: _robot(t, "twice.yaml", text=SSRMS_YAML.read_text() + "\nname: again\n"), "is given twice"),
    (lambda t: _robot(t, "huge.yaml", text="# " + "x" * (5 << 20) + "\n"), "larger than 4 MiB"),
    (lambda t: _special(t, "fifo.yaml", fifo=True), "is a FIFO"),
    (lambda t: _special(t, "folder.yaml", folder=True), "is a directory"),
    (lambda t: _robot(t, "list.yaml", text="- name: arm\n- dh: {}\n"), "a robot file must be a mapping"),
    (lambda t: _robot(t, "python_tag.yaml", text="name: !!python/object/apply:os.system ['true']\n"), "malformed YAML"),
    (lambda t: _urdf_at(t, "urdf_dev.yaml", "/dev/zero"), "urdf.path = '/dev/zero': not a regular file"),
    (lambda t: _urdf_at(t, "urdf_fifo.yaml", _special(t, "arm.urdf", fifo=True)), "not a regular file"),
    (lambda t: _urdf_at(t, "urdf_dir.yaml", str(t)), "not a regular file"),
]

_BOMB = "name: r\nz: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"z{k}: &a{k} [{', '.join([f'*a{k - 1}' if k > 1 else '*a'] * 9)}]\n" for k in range(1, 9))


def _special(tmp: Path, name: str, fifo: bool = False, folder: bool = False) -> str:
    path = tmp / name
    os.mkfifo(path) if fifo else path.mkdir()
    return str(path)


def _urdf_at(tmp: Path, name: str, urdf: str) -> str:
    (tmp / name).write_text(yaml.safe_dump({"name": "arm", "urdf": {"path": urdf, "ee_frame": "tool0"}}))
    return str(tmp / name)


def _tree_digest(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


def _run(workdir: Path, config: Path):
    cmd = ["snakemake", "all", "-s", str(ROOT / "Snakefile"), "-d", str(workdir), "--cores", "1", "--nolock",
           "--configfile", str(config)]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300)


def _check(res, expect: str, name: str | None) -> str | None:
    """None when the run failed as it should, else what went wrong."""
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("capmap:")]
    if res.returncode != 1:
        return f"exit status {res.returncode}"
    if len(lines) != 1:
        return f"{len(lines)} capmap lines: {lines}; stderr tail: {res.stderr[-800:]}"
    if expect not in lines[0] or (name and name not in lines[0]):
        return f"line does not name {expect!r}{f' and {name!r}' if name else ''}: {lines[0]}"
    if "Traceback" in res.stdout + res.stderr:
        return "a traceback was printed"
    return None


def _jobs(tmp_path: Path) -> list[tuple[Path, str, str | None, str]]:
    """(config file, expected text, a name the line must hold, label) of every case."""
    jobs = []
    for changes, expect in CONFIG_CASES + NEW_CONFIG_CASES:
        jobs.append((config_file(tmp_path, **changes), expect, None, f"config {changes}"))
    for make, expect in ROBOT_CASES + NEW_ROBOT_CASES:
        robot = make(tmp_path)
        jobs.append((config_file(tmp_path, robot=robot), expect, Path(robot).name, f"robot file {Path(robot).name}"))
    for make, expect in CLOUD_CASES:
        cloud = make(tmp_path)
        jobs.append((config_file(tmp_path, **{"dualarm.cloud": {"file": cloud, "viewpoints_m": [[0, 0, 1]]}}), expect,
                     "dualarm.cloud.file",
                     f"cloud file {Path(cloud).name}"))
    assert len(NEW_CONFIG_CASES) + len(NEW_ROBOT_CASES) + len(CLOUD_CASES) >= 40
    assert len(jobs) >= 100
    return jobs


def _in_process(config: Path) -> subprocess.CompletedProcess:
    """What the workflow runs before any job (Snakefile: run_document; common.smk: check_run_config),
    in this process, as a finished snakemake call would report it."""
    try:
        check_run_config(run_document([str(config)]), str(config))
    except CapmapError as exc:
        return subprocess.CompletedProcess([], 1, "", f"capmap: {exc}\n")
    return subprocess.CompletedProcess([], 0, "", "")


def test_every_bad_input_is_one_line_naming_it(tmp_path):
    """Every case through the checks the workflow runs before any job (fast: in this process)."""
    failures = [f"{label}: {err}" for cfg, expect, name, label in _jobs(tmp_path)
                if (err := _check(_in_process(cfg), expect, name))]
    assert not failures, "\n".join(failures)


@pytest.mark.slow  # on a finished tiny run: .ci/run runs it (-m slow)
def test_bad_inputs_cost_no_output_through_snakemake(run_dir, tmp_path):
    """A case of each kind (file, YAML, schema, robot, lock, pose, size, step count, cloud) through
    ``snakemake all`` over a finished run: status 1, one capmap line, every output byte-identical."""
    work, _ = run_dir
    before = _tree_digest(work / "results")
    jobs = _jobs(tmp_path)
    pick = ("limts", "q_start_deg has 3 values", "lock.joint = 9", "task.goal_m = [30", "not a finite number",
            "is text, not a number", "voxels.edge_m: this map needs", "verification.dt_s: verifying",
            "lies outside the map's grid", "follow.ground.line_m = [0, 1e-12", "reconfig.dt_s: the reconfiguration",
            "__use_yte__", "no such file", "not a text", "nested deeper", "is a FIFO", "not valid XML", "no column x_m")
    chosen = [j for key in pick for j in jobs if key in j[1]][:len(pick) + 2]
    assert len({j[1] for j in chosen}) >= len(pick)
    with ThreadPoolExecutor(max_workers=3) as pool:
        results = list(pool.map(lambda j: (j, _run(work, j[0])), chosen))
    failures = [f"{j[3]}: {err}" for j, res in results if (err := _check(res, j[1], j[2]))]
    assert not failures, "\n".join(failures)
    assert _tree_digest(work / "results") == before  # every existing output byte-identical


@pytest.mark.parametrize("text", ["", "\x00\x01\x02 binary", "robot: [unclosed"])
def test_a_bad_default_config_is_one_line(tmp_path, text):
    """The default config (no --configfile) is read by capmap before Snakemake sees it."""
    (tmp_path / "config").mkdir()
    (tmp_path / "config" / "config.yaml").write_text(text)
    res = subprocess.run(["snakemake", "all", "-s", str(ROOT / "Snakefile"), "-d", str(tmp_path), "--cores", "1"],
                         capture_output=True, text=True, timeout=300)
    lines = [ln for ln in res.stderr.splitlines() if ln.startswith("capmap:")]
    assert res.returncode == 1 and len(lines) == 1 and "config/config.yaml" in lines[0], res.stderr[-1500:]


# --- what a job used to meet first: drive terms, URDF limits, joint counts, foreign files, cloud values and sizes ---

def _reliability_jobs(tmp_path: Path) -> list:
    from tests.workflow.reliability_cases import RELIABILITY_CASES

    assert len(RELIABILITY_CASES) >= 30
    return [(make(tmp_path), expect, name, absent, label) for make, expect, name, absent, label in RELIABILITY_CASES]


def _check_absent(res, absent: str | None) -> str | None:
    if absent and absent in res.stderr:
        return f"the line echoes what the file holds ({absent!r}): {res.stderr.strip()[:300]}"
    return None


def test_what_a_job_met_first_is_one_line_before_any_job(tmp_path):
    """Each case through the checks the workflow runs before any job: one line naming the file or key,
    nothing the file holds echoed."""
    failures = [f"{label}: {err}" for cfg, expect, name, absent, label in _reliability_jobs(tmp_path)
                if (err := _check(res := _in_process(cfg), expect, name) or _check_absent(res, absent))]
    assert not failures, "\n".join(failures)


@pytest.mark.slow  # on a finished tiny run: .ci/run runs it (-m slow)
def test_what_a_job_met_first_costs_no_output_through_snakemake(run_dir, tmp_path):
    """A case of each family (drive terms, URDF limits, joint count, foreign file, cloud values, fit size,
    scan noise) through ``snakemake all`` over a finished run: status 1, one line, every output
    byte-identical (before, each was met inside a job, after Snakemake had deleted that job's outputs)."""
    work, _ = run_dir
    before = _tree_digest(work / "results")
    pick = ("overflows a float64", "joint elbow_joint's limits", "the capacity map needs 6", "not a capmap robot file",
            "1 points are not finite", "dualarm.fit.cell_m = 1e-09 m", "dualarm.cloud.noise_m = 1e+06 m is larger")
    jobs = _reliability_jobs(tmp_path)
    chosen = [next(j for j in jobs if key in j[1]) for key in pick]
    with ThreadPoolExecutor(max_workers=3) as pool:
        results = list(pool.map(lambda j: (j, _run(work, j[0])), chosen))
    failures = [f"{j[4]}: {err}" for j, res in results if (err := _check(res, j[1], j[2]) or _check_absent(res, j[3]))]
    assert not failures, "\n".join(failures)
    assert _tree_digest(work / "results") == before


@pytest.mark.slow  # on a copy of a finished tiny run: .ci/run runs it (-m slow)
def test_a_path_the_arm_cannot_follow_is_a_result_and_the_run_succeeds(run_dir, tmp_path):
    """The ground robot's shoulder pan with 10^6 N m of Coulomb friction (a finite drive term; its limit is
    14 N m): the arm cannot start forward. ``snakemake all`` succeeds; the follow case's summary says why,
    its figures show it; every output that does not depend on the ground case is byte-identical."""
    import shutil

    from tests.workflow.reliability_cases import _drives

    work = tmp_path / "run"
    shutil.copytree(run_dir[0], work, symlinks=True)
    before = _tree_digest(work / "results")
    cfg = _drives(tmp_path, "stuck.yaml", friction={"coulomb_nm": 1e6, "viscous_nms": 1.5})
    res = _run(work, cfg)
    assert res.returncode == 0, res.stderr[-3000:]
    after = _tree_digest(work / "results")
    run = next(p for p in (work / "results").iterdir() if p.is_dir())
    import pandas as pd

    row = pd.read_csv(run / "follow" / "ground" / "summary.csv").iloc[0]
    assert not row.feasible and "needs 1000000.00 N m, above its limit 14 N m" in row.reason
    changed = {k for k in before if after.get(k) != before[k]}
    allowed = ("/follow/ground/", "/follow/summary.", "/report/", "/catalogue.parquet", "/logs/")  # and the logs of those jobs
    assert changed, "nothing reran"
    unexpected = sorted(k for k in changed if not any(a in "/" + k for a in allowed))
    assert not unexpected, unexpected


@pytest.mark.slow
def test_capmap_run_refuses_a_template_over_a_finished_run(run_dir, tmp_path):
    """`capmap run` with a YTE config over a finished run: one line, nothing run, every output byte-identical."""
    work, cfg = run_dir
    before = _tree_digest(work / "results")
    yte = tmp_path / "yte.yaml"
    yte.write_text("__use_yte__: true\n" + cfg.read_text().replace("run: tiny", f"run: ?__import__('os').system("
                                                                                f"'touch {tmp_path}/pwned')"))
    res = subprocess.run(["capmap", "run", str(yte)], capture_output=True, text=True, timeout=300, cwd=work)
    assert _check(res, "capmap does not evaluate YTE templates", "yte.yaml") is None, res.stderr
    assert not (tmp_path / "pwned").exists()
    assert _tree_digest(work / "results") == before


@pytest.mark.slow
def test_jobs_that_cannot_fit_side_by_side_cost_no_output(run_dir, tmp_path):
    """A finished run asked again with 256 shards on 256 cores: more memory side by side than this machine has.
    One line naming the cores that fit, before any job; every output byte-identical."""
    work, _ = run_dir
    before = _tree_digest(work / "results")
    cfg = config_file(tmp_path, shards=256)
    res = subprocess.run(["snakemake", "all", "-s", str(ROOT / "Snakefile"), "-d", str(work), "--cores", "256",
                          "--nolock", "--config", f"configfile={cfg}"], capture_output=True, text=True, timeout=300)
    assert _check(res, "--cores 256: 256 jobs", None) is None, res.stderr[-1500:]
    assert _tree_digest(work / "results") == before


@pytest.mark.slow
@pytest.mark.skipif(os.geteuid() != 0, reason="mounts a small tmpfs (a disk that fills): needs root")
def test_a_full_disk_over_a_finished_run_is_one_line_and_leaves_no_temp_file(run_dir, tmp_path):
    """A copy of a finished run on a disk with ~64 kB left, asked for a finer follow case (its jobs rerun and write
    megabytes): the job that meets the full disk fails with one capmap line naming the file, leaves no temp file,
    and every output of a job that did not rerun is byte-identical."""
    import shutil

    disk = tmp_path / "disk"
    disk.mkdir()
    size = sum(p.stat().st_size for p in run_dir[0].rglob("*") if p.is_file()) + 16 * 2**20
    subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(disk)], check=True)
    try:
        work = disk / "run"
        shutil.copytree(run_dir[0], work, symlinks=True)
        before = _tree_digest(work / "results")
        free = shutil.disk_usage(disk).free
        (disk / "filler").write_bytes(b"\0" * max(free - 64 * 1024, 0))
        res = _run(work, config_file(tmp_path, **{"follow.period_s": 0.0005, "follow.store_period_s": 0.0005}))
        lines = [ln for ln in res.stderr.splitlines() if ln.startswith("capmap: cannot write")]
        assert res.returncode == 1 and lines and "No space left on device" in lines[0], res.stderr[-2500:]
        assert not list((work / "results").rglob("*.tmp.parquet"))
        after = _tree_digest(work / "results")
        kept = {k: v for k, v in before.items() if "/follow/" not in "/" + k and "/logs/" not in "/" + k
                and "catalogue" not in k and "/report/" not in "/" + k}
        assert {k: after.get(k) for k in kept} == kept
    finally:  # a process still leaving the run's folder would keep the disk busy: detached then (umount -l)
        if subprocess.run(["umount", str(disk)], check=False).returncode != 0:
            subprocess.run(["umount", "-l", str(disk)], check=False)
