"""Bad inputs a job used to meet first (and fail on, after Snakemake had deleted its earlier outputs),
now each one ``capmap:`` line before any job: drive terms, URDF limits, joint counts, foreign files
(named, never echoed), cloud values, the sizes a cloud and its fit imply. Each case: (maker of the
config file from a tmp folder, text the line holds, a name it must hold or None, text it must NOT hold
(what a foreign file holds) or None, label)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq
import yaml

from capmap.config.robot_file import package_file
from tests.scenario import ROOT
from tests.workflow.runs import config_file

NAN, INF = math.nan, math.inf
ROBOTS = ROOT / "config" / "robots"
VIEWS3 = [[0.1, 0.0, 0.75], [0.3, 0.5, 0.2], [0.3, -0.5, 0.2]]  # the tiny config's three cameras


def _doc(name: str) -> dict:
    return yaml.safe_load((ROBOTS / name).read_text())


def _write(tmp: Path, name: str, doc=None, text: str | None = None) -> str:
    path = tmp / name
    path.write_text(text if text is not None else yaml.safe_dump(doc))
    return str(path)


def _drives(tmp: Path, name: str, **entry) -> Path:
    """The default ground robot (UR5 on drives) with its shoulder pan's drive entry changed."""
    doc = _doc("ur5_drives.yaml")
    doc["drives"]["shoulder_pan_joint"].update(entry)
    return config_file(tmp, **{"follow.ground.robot": _write(tmp, name, doc)})


def _ur5_limits(tmp: Path, name: str, joint: str, lower: str, upper: str) -> Path:
    """The UR5 URDF with one joint's limits replaced, as the ground robot."""
    text = Path(package_file("example-robot-data", "robots/ur_description/urdf/ur5_robot.urdf", "test")).read_text()
    i = text.index(f'name="{joint}"')
    j, k = text.index("<limit", i), text.index("/>", text.index("<limit", i))
    limit = re.sub(r'upper="[^"]+"', f'upper="{upper}"', re.sub(r'lower="[^"]+"', f'lower="{lower}"', text[j:k]))
    (tmp / f"{name}.urdf").write_text(text[:j] + limit + text[k:])
    robot = _write(tmp, f"{name}.yaml", {"name": name, "urdf": {"path": f"{name}.urdf", "ee_frame": "tool0"},
                                         "gravity_mps2": [0, 0, -9.81]})
    return config_file(tmp, **{"follow.ground.robot": robot})


def _joints(tmp: Path, name: str, n: int) -> Path:
    """The SSRMS-type arm with n joints (rows repeated or dropped), as the capacity map's robot."""
    doc = _doc("ssrms7.yaml")
    for key in ("links", "joint_range_deg"):
        doc[key] = (doc[key] * 2)[:n]
    doc["dh"]["rows"] = (doc["dh"]["rows"] * 2)[:n]
    q = ([100, 124, 98, 130, 146, 174, 57] * 2)[:n]
    return config_file(tmp, robot=_write(tmp, name, doc), **{"task.q_ini_deg": q})


FOREIGN = "version: '3'\nservices:\n  db_secret_service: {image: postgres}\n"  # another tool's YAML


def _foreign(tmp: Path, key: str, name: str) -> Path:
    return config_file(tmp, **{key: _write(tmp, name, text=FOREIGN)})


def _cloud(tmp: Path, name: str, rows: list[str] | None = None, header: str = "x_m,y_m,z_m,viewpoint",
           views=VIEWS3, parquet: dict | None = None) -> Path:
    path = tmp / name
    if parquet is not None:
        pq.write_table(pa.table(parquet), path)
    else:
        path.write_text("\n".join([header, *(rows or [])]) + "\n")
    return config_file(tmp, **{"dualarm.cloud": {"file": str(path), "viewpoints_m": views}})


_GOOD = [f"{0.01 * i},{0.02 * i},0.5,{i % 3}" for i in range(12)]  # twelve finite points, three cameras

RELIABILITY_CASES = [
    # drive terms: finite each, and so their product (the reflected inertia)
    (lambda t: _drives(t, "overflow.yaml", rotor_inertia_kgm2=1e300, gear_ratio=1e10), "overflows a float64",
     "overflow.yaml", None, "rotor inertia x gear ratio^2 overflows"),
    (lambda t: _drives(t, "overflow2.yaml", rotor_inertia_kgm2=1e-4, gear_ratio=1e160), "gear_ratio^2",
     "drives.shoulder_pan_joint", None, "a gear ratio whose square overflows"),
    (lambda t: _drives(t, "coulomb_inf.yaml", friction={"coulomb_nm": INF}), "coulomb_nm = inf",
     "coulomb_inf.yaml", None, "infinite Coulomb friction"),
    (lambda t: _drives(t, "viscous_nan.yaml", friction={"viscous_nms": NAN}), "viscous_nms = nan",
     "viscous_nan.yaml", None, "NaN viscous friction"),
    (lambda t: _drives(t, "armature_neg.yaml", rotor_inertia_kgm2=-1.0, gear_ratio=100), "rotor_inertia_kgm2",
     "armature_neg.yaml", None, "a negative rotor inertia"),
    # a URDF's limits in order
    (lambda t: _ur5_limits(t, "ur5_swapped", "elbow_joint", "3.0", "-3.0"), "joint elbow_joint's limits",
     "ur5_swapped", None, "a URDF joint with lower > upper"),
    (lambda t: _ur5_limits(t, "ur5_equal", "wrist_1_joint", "1.0", "1.0"), "lower must be < upper",
     "ur5_equal", None, "a URDF joint with lower = upper"),
    (lambda t: _ur5_limits(t, "ur5_nan", "shoulder_lift_joint", "nan", "1.0"), "cannot be parsed",
     "ur5_nan", None, "a URDF joint with a NaN limit"),
    # the capacity map's arm: 6 joints move once one is locked
    (lambda t: _joints(t, "eight.yaml", 8), "the capacity map needs 6", "eight.yaml", None, "an 8-joint arm"),
    (lambda t: _joints(t, "six.yaml", 6), "so 5 move with one locked", "six.yaml", None, "a 6-joint arm"),
    # files that are not what the key says: named as such, their content not echoed
    (lambda t: _foreign(t, "robot", "compose.yaml"), "not a capmap robot file", "compose.yaml", "secret",
     "another tool's YAML as the robot"),
    (lambda t: _foreign(t, "follow.ground.robot", "compose2.yaml"), "not a capmap robot file", "compose2.yaml",
     "secret", "another tool's YAML as the ground robot"),
    (lambda t: _foreign(t, "reconfig.robot", "compose3.yaml"), "not a capmap robot file", "compose3.yaml", "secret",
     "another tool's YAML as the platform"),
    (lambda t: _foreign(t, "dualarm.scene", "compose4.yaml"), "not a capmap scene file", "compose4.yaml", "secret",
     "another tool's YAML as the scene"),
    (lambda t: _foreign(t, "dualarm.robot", "compose5.yaml"), "not a capmap dual-arm robot file", "compose5.yaml",
     "secret", "another tool's YAML as the dual-arm robot"),
    (lambda t: config_file(t, robot=_write(t, "tagged.yaml", text="name: !!int top_secret_value\n")),
     "not a valid int", "tagged.yaml", "secret", "a tagged value that is not one"),
    (lambda t: config_file(t, robot=_write(t, "dup.yaml", text="secret_key_a: 1\nsecret_key_a: 2\n")),
     "a key is given twice", "dup.yaml", "secret", "a repeated key"),
    (lambda t: config_file(t, robot=_write(t, "date.yaml", text="name: 2024-02-31\n")), "not a valid timestamp",
     "date.yaml", "2024-02-31", "an impossible date"),
    # a user's cloud, value by value (the scan job's own reader, before any job)
    (lambda t: _cloud(t, "nan.csv", ["nan,0,0,0"] + _GOOD), "1 points are not finite", "nan.csv", None,
     "a NaN coordinate"),
    (lambda t: _cloud(t, "inf.csv", ["0,inf,0,1", "0,-inf,0,2"] + _GOOD), "2 points are not finite", "inf.csv",
     None, "infinite coordinates"),
    (lambda t: _cloud(t, "empty.csv", []), "no points", "empty.csv", None, "a header and no points"),
    (lambda t: _cloud(t, "view_high.csv", _GOOD + ["0,0,0,3"]), "column viewpoint must index", "view_high.csv", None,
     "a viewpoint index past the cameras"),
    (lambda t: _cloud(t, "view_neg.csv", _GOOD + ["0,0,0,-1"]), "1 rows do not", "view_neg.csv", None,
     "a negative viewpoint index"),
    (lambda t: _cloud(t, "view_frac.csv", _GOOD + ["0,0,0,0.5"]), "column viewpoint must index", "view_frac.csv",
     None, "a fractional viewpoint index"),
    (lambda t: _cloud(t, "text.csv", _GOOD + ["a,b,c,0"]), "must hold numbers only", "text.csv", None,
     "text in a coordinate"),
    (lambda t: _cloud(t, "few.csv", _GOOD[:9]), "the envelope fit needs at least 10", "few.csv", None,
     "nine points"),
    (lambda t: _cloud(t, "nan.parquet", parquet={"x_m": [NAN] + [0.1 * i for i in range(11)], "y_m": [0.0] * 12,
                                                 "z_m": [0.5] * 12, "viewpoint": [0] * 12}),
     "points are not finite", "nan.parquet", None, "a Parquet cloud with a NaN"),
    (lambda t: _cloud(t, "wide.csv", _GOOD + ["1e7,0,0,0"]), "raise dualarm.fit.cell_m", "wide.csv", None,
     "a cloud 10,000 km across (the fit's grid)"),
    # sizes the synthetic scan and the fit imply
    (lambda t: config_file(t, **{"dualarm.fit.cell_m": 1e-9}), "dualarm.fit.cell_m = 1e-09 m", None, None,
     "a fit cell of a nanometre"),
    (lambda t: config_file(t, **{"dualarm.fit.cell_m": 1e-5}), "raise dualarm.fit.cell_m", None, None,
     "a fit cell of 10 micrometres"),
    (lambda t: config_file(t, **{"dualarm.cloud.noise_m": 1e6}), "dualarm.cloud.noise_m = 1e+06 m is larger", None,
     None, "a scan noise of 1000 km"),
    (lambda t: config_file(t, **{"dualarm.cloud.noise_m": 10.0}), "larger than the scene it scans", None, None,
     "a scan noise larger than the scene"),
]
