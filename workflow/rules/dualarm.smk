# Method family 4: dual arms in a confined space. scan -> envelope; capsules; -> optimise, check; -> plots, animation.
DUALARM_SLICES = dualarm_slices(config)
DUALARM = bool(DUALARM_SLICES)


def dualarm_json(rule):
    return canonical(DUALARM_SLICES[rule])


def dualarm_files(*keys):
    """Input files of the dual-arm section (the scene, the robot file, a user's cloud)."""
    da = config.get("dualarm", {})
    return [da[k] for k in keys if k in da] + ([da["cloud"]["file"]] if "scene" in keys and "file" in da.get("cloud", {}) else [])


rule dualarm_scan:
    """The scene's point cloud: a synthetic partial scan with noise, or the user's file."""
    input:
        dualarm_files("scene"),
    output:
        "results/dualarm/cloud.parquet",
    params:
        slice=lambda w: with_code(dualarm_json("scan"), "dualarm_scan"),
    log:
        "results/logs/dualarm/scan.log",
    script:
        "../scripts/dualarm_scan.py"


rule dualarm_envelope:
    """Swept triangles and capsules fitted to the cloud; every point checked inside one."""
    input:
        cloud="results/dualarm/cloud.parquet",
        files=dualarm_files("scene"),
    output:
        "results/dualarm/environment.parquet",
    params:
        slice=lambda w: with_code(dualarm_json("envelope"), "dualarm_envelope"),
    log:
        "results/logs/dualarm/envelope.log",
    script:
        "../scripts/dualarm_envelope.py"


rule dualarm_capsules:
    """Minimum-volume capsules over the robot's URDF collision geometry (coverage checked)."""
    input:
        dualarm_files("robot"),
    output:
        "results/dualarm/robot_capsules.parquet",
    params:
        slice=lambda w: with_code(dualarm_json("capsules"), "dualarm_capsules"),
    log:
        "results/logs/dualarm/capsules.log",
    script:
        "../scripts/dualarm_capsules.py"


rule dualarm_optimise:
    """Augmented-Lagrangian DDP of the panel assembly; errors and safety on a finer grid."""
    input:
        environment="results/dualarm/environment.parquet",
        capsules="results/dualarm/robot_capsules.parquet",
        files=dualarm_files("scene", "robot"),
    output:
        trajectory="results/dualarm/trajectory.parquet",
        fine="results/dualarm/fine.parquet",
        outer="results/dualarm/outer.parquet",
        csv=report("results/dualarm/summary.csv", category="Dual-arm assembly", caption="../report/dualarm_summary.rst"),
        md="results/dualarm/summary.md",
    params:
        slice=lambda w: with_code(dualarm_json("optimise"), "dualarm_optimise"),
    log:
        "results/logs/dualarm/optimise.log",
    script:
        "../scripts/dualarm_optimise.py"


rule dualarm_check:
    """The equality-only problem by AL-FDDP and by mim-solvers CSQP: the same optimum?"""
    input:
        environment="results/dualarm/environment.parquet",
        capsules="results/dualarm/robot_capsules.parquet",
        files=dualarm_files("scene", "robot"),
    output:
        csv=report("results/dualarm/csqp_check.csv", category="Dual-arm assembly", caption="../report/dualarm_check.rst"),
        md="results/dualarm/csqp_check.md",
    params:
        slice=lambda w: with_code(dualarm_json("check"), "dualarm_check"),
    log:
        "results/logs/dualarm/check.log",
    script:
        "../scripts/dualarm_check.py"


rule dualarm_plots:
    """Constraint errors, safety distances, joints and velocities vs limits, convergence."""
    input:
        trajectory="results/dualarm/trajectory.parquet",
        fine="results/dualarm/fine.parquet",
        outer="results/dualarm/outer.parquet",
    output:
        errors=report("results/dualarm/constraint_errors.png", category="Dual-arm assembly",
                      caption="../report/dualarm_errors.rst"),
        distances=report("results/dualarm/distances.png", category="Dual-arm assembly",
                         caption="../report/dualarm_distances.rst"),
        joints=report("results/dualarm/joints.png", category="Dual-arm assembly", caption="../report/dualarm_joints.rst"),
        velocities=report("results/dualarm/velocities.png", category="Dual-arm assembly",
                          caption="../report/dualarm_joints.rst"),
        convergence=report("results/dualarm/convergence.png", category="Dual-arm assembly",
                           caption="../report/dualarm_convergence.rst"),
    params:
        code=with_code("{}", "dualarm_plots"),
    log:
        "results/logs/dualarm/plots.log",
    script:
        "../scripts/dualarm_plots.py"


rule dualarm_animation:
    """Offline 3D animation (MeshCat static HTML): capsules, the panel, the fitted environment."""
    input:
        trajectory="results/dualarm/trajectory.parquet",
        environment="results/dualarm/environment.parquet",
        capsules="results/dualarm/robot_capsules.parquet",
    output:
        report("results/dualarm/animation.html", category="Dual-arm assembly", caption="../report/dualarm_animation.rst"),
    params:
        slice=lambda w: with_code(dualarm_json("animation"), "dualarm_animation"),
    log:
        "results/logs/dualarm/animation.log",
    script:
        "../scripts/dualarm_animation.py"
