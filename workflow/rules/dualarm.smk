# Method family 4: dual arms in a confined space. scan -> envelope; capsules; -> optimise, check; -> plots, animation.
DUALARM = RUN.dualarm is not None


rule dualarm_scan:
    """The scene's point cloud: a synthetic partial scan with noise, or the user's file."""
    input:
        dualarm_files("scene"),
    output:
        out("dualarm/cloud.parquet"),
    log:
        out("logs/dualarm/scan.log"),
    priority: 10
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda w: params("dualarm_scan", "dualarm_scan"),
    script:
        "../scripts/dualarm_scan.py"


rule dualarm_envelope:
    """Swept triangles and capsules fitted to the cloud; every point checked inside one."""
    input:
        cloud=out("dualarm/cloud.parquet"),
        files=dualarm_files("scene"),
    output:
        out("dualarm/environment.parquet"),
    log:
        out("logs/dualarm/envelope.log"),
    priority: 10
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda w: params("dualarm_envelope", "dualarm_envelope"),
    script:
        "../scripts/dualarm_envelope.py"


rule dualarm_unknown:
    """The space no viewpoint observed inside the work volume (occupied, as boxes)."""
    input:
        cloud=out("dualarm/cloud.parquet"),
        environment=out("dualarm/environment.parquet"),
    output:
        out("dualarm/unknown.parquet"),
    log:
        out("logs/dualarm/unknown.log"),
    priority: 10
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda w: params("dualarm_unknown", "dualarm_unknown"),
    script:
        "../scripts/dualarm_unknown.py"


rule dualarm_capsules:
    """Minimum-volume capsules over the robot's visual and collision geometry, fingers closed on the
    scene's panel (coverage checked)."""
    input:
        dualarm_files("robot") + ([RUN.dualarm.scene] if DUALARM else []),  # the scene's panel: the fingers close on it
    output:
        out("dualarm/robot_capsules.parquet"),
    log:
        out("logs/dualarm/capsules.log"),
    priority: 10
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda w: params("dualarm_capsules", "dualarm_capsules"),
    script:
        "../scripts/dualarm_capsules.py"


rule dualarm_optimise:
    """Augmented-Lagrangian DDP of the panel assembly; errors and safety on a finer grid (against the
    unknown space too); joint torques with the held panel by inverse dynamics."""
    input:
        environment=out("dualarm/environment.parquet"),
        unknown=out("dualarm/unknown.parquet"),
        capsules=out("dualarm/robot_capsules.parquet"),
        files=dualarm_files("scene", "robot"),
    output:
        trajectory=out("dualarm/trajectory.parquet"),
        fine=out("dualarm/fine.parquet"),
        outer=out("dualarm/outer.parquet"),
        torques=out("dualarm/torques.parquet"),
        csv=out("dualarm/summary.csv"),
        md=out("dualarm/summary.md"),
    log:
        out("logs/dualarm/optimise.log"),
    priority: 10
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda w: params("dualarm_optimise", "dualarm_optimise"),
    script:
        "../scripts/dualarm_optimise.py"


rule dualarm_check:
    """The equality-only problem by AL-FDDP and by mim-solvers CSQP: the same optimum?"""
    input:
        environment=out("dualarm/environment.parquet"),
        capsules=out("dualarm/robot_capsules.parquet"),
        files=dualarm_files("scene", "robot"),
    output:
        csv=out("dualarm/csqp_check.csv"),
        md=out("dualarm/csqp_check.md"),
    log:
        out("logs/dualarm/check.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda w: params("dualarm_check", "dualarm_check"),
    script:
        "../scripts/dualarm_check.py"


rule dualarm_plots:
    """Constraint errors, safety distances, joints and velocities vs limits, torques vs effort limits,
    convergence."""
    input:
        trajectory=out("dualarm/trajectory.parquet"),
        fine=out("dualarm/fine.parquet"),
        outer=out("dualarm/outer.parquet"),
        torques=out("dualarm/torques.parquet"),
    output:
        errors=report(
            out("dualarm/constraint_errors.png"), category="Dual-arm assembly", caption="../report/dualarm_errors.rst"
        ),
        distances=report(
            out("dualarm/distances.png"), category="Dual-arm assembly", caption="../report/dualarm_distances.rst"
        ),
        joints=report(out("dualarm/joints.png"), category="Dual-arm assembly", caption="../report/dualarm_joints.rst"),
        velocities=report(
            out("dualarm/velocities.png"), category="Dual-arm assembly", caption="../report/dualarm_joints.rst"
        ),
        torques=report(
            out("dualarm/torques.png"), category="Dual-arm assembly", caption="../report/dualarm_torques.rst"
        ),
        convergence=report(
            out("dualarm/convergence.png"), category="Dual-arm assembly", caption="../report/dualarm_convergence.rst"
        ),
    log:
        out("logs/dualarm/plots.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        code=code_params("dualarm_plots"),
    script:
        "../scripts/dualarm_plots.py"


rule dualarm_animation:
    """Offline 3D animation (MeshCat static HTML): capsules, the panel, the fitted environment."""
    input:
        trajectory=out("dualarm/trajectory.parquet"),
        environment=out("dualarm/environment.parquet"),
        capsules=out("dualarm/robot_capsules.parquet"),
    output:
        report(out("dualarm/animation.html"), category="Dual-arm assembly", caption="../report/dualarm_animation.rst"),
    log:
        out("logs/dualarm/animation.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda w: params("dualarm_animation", "dualarm_animation"),
    script:
        "../scripts/dualarm_animation.py"
