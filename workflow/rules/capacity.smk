# Method family 1: capacity map -> plan -> verify (one plan/verify job per payload).
# priority 20: the capacity map's chain (model .. voxel_map) is the run's critical path, so it goes first;
# 10: the long jobs of the other families (dual-arm envelope .. optimise, follow) start before the short ones.


rule model:
    """Load and validate the robot; write its joint/link table."""
    input:
        robot=RUN.robot,
    output:
        out("model/joints.parquet"),
    log:
        out("logs/model.log"),
    priority: 20
    conda:
        "../envs/capmap.yaml"
    params:
        slice=params("model", "model"),
    script:
        "../scripts/model.py"


rule sample:
    """Monte Carlo workspace of the locked arm (seeded)."""
    input:
        model=out("model/joints.parquet"),
    output:
        temp(out("sample/points.parquet")),
    log:
        out("logs/sample.log"),
    priority: 20
    conda:
        "../envs/capmap.yaml"
    params:
        slice=params("sample", "sample"),
    script:
        "../scripts/sample.py"


rule capacity:
    """Shard k of n: every IK branch at the task orientation x every direction, per point."""
    input:
        points=out("sample/points.parquet"),
    output:
        temp(out("capacity/shard_{k}_of_{n}.parquet")),
    log:
        out("logs/capacity/shard_{k}_of_{n}.log"),
    wildcard_constraints:
        k=r"\d+",
        n=r"\d+",
    priority: 20
    conda:
        "../envs/capmap.yaml"
    resources:
        mem_mb=mem_mb("capacity"),
    params:
        slice=params("capacity", "capacity"),
    script:
        "../scripts/capacity.py"


rule points:
    """The capacity shards gathered into one per-point table (the shards are temporary)."""
    input:
        shards=expand(out("capacity/shard_{k}_of_{n}.parquet"), k=range(SHARDS), n=SHARDS),
    output:
        out("capacity/points.parquet"),
    log:
        out("logs/points.log"),
    priority: 20
    conda:
        "../envs/capmap.yaml"
    resources:
        mem_mb=mem_mb("voxels"),
    params:
        slice=params("capacity", "points"),
    script:
        "../scripts/points.py"


rule voxels:
    """The voxel grid over the points (minimum capacity over the sampled points per voxel)."""
    input:
        points=out("capacity/points.parquet"),
    output:
        voxels=temp(out("voxels/sampled.parquet")),
    log:
        out("logs/voxels.log"),
    priority: 20
    conda:
        "../envs/capmap.yaml"
    resources:
        mem_mb=mem_mb("voxels"),
    params:
        slice=params("voxels", "voxels"),
    script:
        "../scripts/voxels.py"


rule refine:
    """Shard k of n of the reachable voxels: each voxel's minimum refined until it converges, all branches and
    each configuration."""
    input:
        voxels=out("voxels/sampled.parquet"),
    output:
        voxels=temp(out("voxels/refined_{k}_of_{n}.parquet")),
        configurations=temp(out("voxels/configurations_{k}_of_{n}.parquet")),
    log:
        out("logs/refine/shard_{k}_of_{n}.log"),
    wildcard_constraints:
        k=r"\d+",
        n=r"\d+",
    priority: 20
    conda:
        "../envs/capmap.yaml"
    resources:
        mem_mb=mem_mb("refine"),
    params:
        slice=params("refine", "refine"),
    script:
        "../scripts/refine.py"


rule voxel_map:
    """The voxel map every later stage reads: the sampled voxels with their refined values; the map per
    configuration."""
    input:
        sampled=out("voxels/sampled.parquet"),
        refined=expand(out("voxels/refined_{k}_of_{n}.parquet"), k=range(SHARDS), n=SHARDS) if REFINE else [],
        configurations=(
            expand(out("voxels/configurations_{k}_of_{n}.parquet"), k=range(SHARDS), n=SHARDS) if REFINE else []
        ),
    output:
        voxels=out("voxels/voxels.parquet"),
        configurations=out("voxels/configurations.parquet"),
    log:
        out("logs/voxel_map.log"),
    priority: 20
    conda:
        "../envs/capmap.yaml"
    resources:
        mem_mb=mem_mb("maps"),
    params:
        slice=params("refine", "voxel_map"),
    script:
        "../scripts/voxel_map.py"


rule summary:
    """Capacity summary table and workspace figure (in the report)."""
    input:
        voxels=out("voxels/voxels.parquet"),
        configurations=out("voxels/configurations.parquet"),
        points=out("capacity/points.parquet"),
        waypoints=expand(out("plan/payload_{payload}kg/waypoints.parquet"), payload=PAYLOADS),
        verified=expand(out("verify/payload_{payload}kg/summary.csv"), payload=PAYLOADS),
    output:
        csv=out("summary/capacity_summary.csv"),
        md=out("summary/capacity_summary.md"),
        png=report(out("summary/capacity_map.png"), category="Capacity map", caption="../report/capacity_map.rst"),
    log:
        out("logs/summary.log"),
    conda:
        "../envs/capmap.yaml"
    resources:
        mem_mb=mem_mb("maps"),
    params:
        slice=params("view", "summary"),
    script:
        "../scripts/summary.py"


rule capacity_3d:
    """Interactive 3D view of the map (self-contained HTML): voxels by capacity, payload and height
    sliders, the payloads' and the further tasks' paths."""
    input:
        voxels=out("voxels/voxels.parquet"),
        configurations=out("voxels/configurations.parquet"),
        waypoints=expand(out("plan/payload_{payload}kg/waypoints.parquet"), payload=PAYLOADS),
        tasks=expand(out("tasks/{task}/waypoints.parquet"), task=TASKS),
        verified=expand(out("verify/payload_{payload}kg/summary.csv"), payload=PAYLOADS)
        + expand(out("tasks/{task}/summary.csv"), task=TASKS),
    output:
        report(out("summary/capacity_3d.html"), category="Capacity map", caption="../report/capacity_3d.rst"),
    log:
        out("logs/capacity_3d.log"),
    conda:
        "../envs/capmap.yaml"
    resources:
        mem_mb=mem_mb("maps"),
    params:
        slice=params("view", "capacity_3d"),
        tasks=TASKS,  # the further tasks' names, in the order of input.tasks (the paths' labels)
    script:
        "../scripts/capacity_3d.py"


rule plan:
    """Improved A* through the voxels that carry the payload: one job per task payload (plan/payload_<m>kg)
    and per further task (tasks/<name>)."""
    input:
        voxels=out("voxels/voxels.parquet"),
    output:
        out("{plan_dir}/waypoints.parquet"),
    log:
        out("logs/{plan_dir}/plan.log"),
    wildcard_constraints:
        plan_dir=PLAN_DIR_RE,
    conda:
        "../envs/capmap.yaml"
    resources:
        mem_mb=mem_mb("plan"),
    params:
        slice=lambda w: params("plan", "plan", job_of(w.plan_dir)),
    script:
        "../scripts/plan.py"


rule verify:
    """Direct line and planned path: trapezoidal timing, continuous-branch IK, loads carrying the payload
    (verify/payload_<m>kg, tasks/<name>)."""
    input:
        waypoints=lambda w: out(f"{plan_dir_of(w.verify_dir)}/waypoints.parquet"),
    output:
        timeseries=out("{verify_dir}/timeseries.parquet"),
        segments=out("{verify_dir}/segments.parquet"),
        csv=out("{verify_dir}/summary.csv"),
        md=out("{verify_dir}/summary.md"),
    log:
        out("logs/{verify_dir}/verify.log"),
    wildcard_constraints:
        verify_dir=VERIFY_DIR_RE,
    conda:
        "../envs/capmap.yaml"
    resources:
        mem_mb=mem_mb("verify"),
    params:
        slice=lambda w: params("verify", "verify", job_of(w.verify_dir)),
    script:
        "../scripts/verify.py"


rule verify_plots:
    """Capacity workspace with both paths; torques, base force and moment against their limits."""
    input:
        voxels=out("voxels/voxels.parquet"),
        configurations=out("voxels/configurations.parquet"),
        timeseries=out("{verify_dir}/timeseries.parquet"),
    output:
        workspace=report(
            out("{verify_dir}/workspace.png"),
            category="Verification",
            subcategory="{verify_dir}",
            caption="../report/workspace.rst",
        ),
        torques=report(
            out("{verify_dir}/torques.png"),
            category="Verification",
            subcategory="{verify_dir}",
            caption="../report/loads.rst",
        ),
        force=report(
            out("{verify_dir}/base_force.png"),
            category="Verification",
            subcategory="{verify_dir}",
            caption="../report/loads.rst",
        ),
        moment=report(
            out("{verify_dir}/base_moment.png"),
            category="Verification",
            subcategory="{verify_dir}",
            caption="../report/loads.rst",
        ),
    log:
        out("logs/{verify_dir}/plots.log"),
    wildcard_constraints:
        verify_dir=VERIFY_DIR_RE,
    conda:
        "../envs/capmap.yaml"
    resources:
        mem_mb=mem_mb("maps"),
    params:
        slice=lambda w: params("verify", "verify_plots", job_of(w.verify_dir)),
        colour=lambda w: path_colour_of(w.verify_dir),  # the planned path's, as on the summary map and 3D page
    script:
        "../scripts/verify_plots.py"


rule verify_summary:
    """Every payload's and further task's verification in one table (in the report)."""
    input:
        expand(out("verify/payload_{payload}kg/summary.csv"), payload=PAYLOADS),
        expand(out("tasks/{task}/summary.csv"), task=TASKS),
    output:
        csv=out("verify/summary.csv"),
        md=out("verify/summary.md"),
    log:
        out("logs/verify/summary.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        code=code_params("verify_summary"),
    script:
        "../scripts/verify_summary.py"


rule plan_gain:
    """Random tasks on this map planned with isotropic and direction-aware moves; gains verified."""
    input:
        voxels=out("voxels/voxels.parquet"),
    output:
        tasks=out("plan/gain_tasks.parquet"),
        csv=out("plan/gain.csv"),
        md=out("plan/gain.md"),
    log:
        out("logs/plan/gain.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        slice=params("gain", "plan_gain"),
    script:
        "../scripts/plan_gain.py"


rule gain_catalogue:
    """Catalogue of the plan-gain experiment's dataset."""
    input:
        out("plan/gain_tasks.parquet"),
    output:
        out("plan/gain_catalogue.parquet"),
    log:
        out("logs/plan/gain_catalogue.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        code=code_params("catalogue"),
    script:
        "../scripts/catalogue.py"


rule experiments:
    """Target (not in all): the plan-gain experiment, isotropic against direction-aware moves on this map."""
    input:
        out("plan/gain.csv"),
        out("plan/gain.md"),
        out("plan/gain_catalogue.parquet"),
