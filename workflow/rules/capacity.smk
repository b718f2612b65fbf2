# Method family 1: capacity map -> plan -> verify (one plan/verify job per payload).
# priority 20: the capacity map's chain (model .. voxel_map) is the run's critical path, so it goes first;
# 10: the long jobs of the other families (dual-arm envelope .. optimise, follow) start before the short ones.


rule model:
    """Load and validate the robot; write its joint/link table."""
    input:
        robot=RUN.robot,
    output:
        out("model/joints.parquet"),
    params:
        slice=params("model", "model"),
    log:
        out("logs/model.log"),
    priority: 20
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/model.py"


rule sample:
    """Monte Carlo workspace of the locked arm (seeded)."""
    input:
        model=out("model/joints.parquet"),
    output:
        out("sample/points.parquet"),
    params:
        slice=params("sample", "sample"),
    log:
        out("logs/sample.log"),
    priority: 20
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/sample.py"


rule capacity:
    """Shard k of n: every IK branch at the task orientation x every direction, per point."""
    input:
        points=out("sample/points.parquet"),
    output:
        out("capacity/shard_{k}_of_{n}.parquet"),
    params:
        slice=params("capacity", "capacity"),
    log:
        out("logs/capacity/shard_{k}_of_{n}.log"),
    wildcard_constraints:
        k=r"\d+",
        n=r"\d+",
    priority: 20
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/capacity.py"


rule voxels:
    """Gather the shards into the voxel grid (minimum capacity over the sampled points per voxel)."""
    input:
        shards=expand(out("capacity/shard_{k}_of_{n}.parquet"), k=range(SHARDS), n=SHARDS),
    output:
        voxels=out("voxels/sampled.parquet"),
        points=out("voxels/points.parquet"),
    params:
        slice=params("voxels", "voxels"),
    log:
        out("logs/voxels.log"),
    priority: 20
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/voxels.py"


rule refine:
    """Shard k of n of the reachable voxels: each voxel's minimum refined until it converges, all branches and
    each configuration."""
    input:
        voxels=out("voxels/sampled.parquet"),
    output:
        voxels=out("voxels/refined_{k}_of_{n}.parquet"),
        configurations=out("voxels/configurations_{k}_of_{n}.parquet"),
    params:
        slice=params("refine", "refine"),
    log:
        out("logs/refine/shard_{k}_of_{n}.log"),
    wildcard_constraints:
        k=r"\d+",
        n=r"\d+",
    priority: 20
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/refine.py"


rule voxel_map:
    """The voxel map every later stage reads: the sampled voxels with their refined values; the map per
    configuration."""
    input:
        sampled=out("voxels/sampled.parquet"),
        refined=expand(out("voxels/refined_{k}_of_{n}.parquet"), k=range(SHARDS), n=SHARDS) if REFINE else [],
        configurations=expand(out("voxels/configurations_{k}_of_{n}.parquet"), k=range(SHARDS), n=SHARDS)
        if REFINE
        else [],
    output:
        voxels=out("voxels/voxels.parquet"),
        configurations=out("voxels/configurations.parquet"),
    params:
        slice=params("refine", "voxel_map"),
    log:
        out("logs/voxel_map.log"),
    priority: 20
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/voxel_map.py"


rule summary:
    """Capacity summary table and workspace figure (in the report)."""
    input:
        voxels=out("voxels/voxels.parquet"),
        configurations=out("voxels/configurations.parquet"),
        points=out("voxels/points.parquet"),
        waypoints=expand(out("plan/payload_{payload}kg/waypoints.parquet"), payload=PAYLOADS),
    output:
        csv=out("summary/capacity_summary.csv"),
        md=out("summary/capacity_summary.md"),
        png=report(out("summary/capacity_map.png"), category="Capacity map", caption="../report/capacity_map.rst"),
    params:
        slice=params("view", "summary"),
    log:
        out("logs/summary.log"),
    conda:
        "../envs/capmap.yaml"
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
    output:
        report(out("summary/capacity_3d.html"), category="Capacity map", caption="../report/capacity_3d.rst"),
    params:
        slice=params("view", "capacity_3d"),
        tasks=TASKS,  # the further tasks' names, in the order of input.tasks (the paths' labels)
    log:
        out("logs/capacity_3d.log"),
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/capacity_3d.py"


rule plan:
    """Improved A* through the voxels that carry the task payload (one job per payload)."""
    input:
        voxels=out("voxels/voxels.parquet"),
    output:
        out("plan/payload_{payload}kg/waypoints.parquet"),
    params:
        slice=lambda w: params("plan", "plan", job_of(w)),
    log:
        out("logs/plan/payload_{payload}kg.log"),
    wildcard_constraints:
        payload=PAYLOAD_RE,
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/plan.py"


rule verify:
    """Direct line and planned path: trapezoidal timing, continuous-branch IK, loads carrying the payload."""
    input:
        waypoints=out("plan/payload_{payload}kg/waypoints.parquet"),
    output:
        timeseries=out("verify/payload_{payload}kg/timeseries.parquet"),
        segments=out("verify/payload_{payload}kg/segments.parquet"),
        csv=out("verify/payload_{payload}kg/summary.csv"),
        md=out("verify/payload_{payload}kg/summary.md"),
    params:
        slice=lambda w: params("verify", "verify", job_of(w)),
    log:
        out("logs/verify/payload_{payload}kg.log"),
    wildcard_constraints:
        payload=PAYLOAD_RE,
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/verify.py"


rule verify_plots:
    """Capacity workspace with both paths; torques, base force and moment against their limits."""
    input:
        voxels=out("voxels/voxels.parquet"),
        configurations=out("voxels/configurations.parquet"),
        timeseries=out("verify/payload_{payload}kg/timeseries.parquet"),
    output:
        workspace=report(out("verify/payload_{payload}kg/workspace.png"), category="Verification",
                         subcategory="{payload} kg", caption="../report/workspace.rst"),
        torques=report(out("verify/payload_{payload}kg/torques.png"), category="Verification",
                       subcategory="{payload} kg", caption="../report/loads.rst"),
        force=report(out("verify/payload_{payload}kg/base_force.png"), category="Verification",
                     subcategory="{payload} kg", caption="../report/loads.rst"),
        moment=report(out("verify/payload_{payload}kg/base_moment.png"), category="Verification",
                      subcategory="{payload} kg", caption="../report/loads.rst"),
    params:
        slice=lambda w: params("verify", "verify_plots", job_of(w)),
    log:
        out("logs/verify/plots_payload_{payload}kg.log"),
    wildcard_constraints:
        payload=PAYLOAD_RE,
    conda:
        "../envs/capmap.yaml"
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
    params:
        code=code_params("verify_summary"),
    log:
        out("logs/verify/summary.log"),
    conda:
        "../envs/capmap.yaml"
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
    params:
        slice=params("gain", "plan_gain"),
    log:
        out("logs/plan/gain.log"),
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/plan_gain.py"


rule gain_catalogue:
    """Catalogue of the plan-gain experiment's dataset."""
    input:
        out("plan/gain_tasks.parquet"),
    output:
        out("plan/gain_catalogue.parquet"),
    params:
        code=code_params("catalogue"),
    log:
        out("logs/plan/gain_catalogue.log"),
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/catalogue.py"


rule experiments:
    """Target (not in all): the plan-gain experiment, isotropic against direction-aware moves on this map."""
    input:
        out("plan/gain.csv"),
        out("plan/gain.md"),
        out("plan/gain_catalogue.parquet"),


# Further tasks (config `tasks`): the same plan, verify and plot stages on their own start, goal,
# payload and start configuration, one job each, under results/<run>/tasks/<name>/.


rule plan_task:
    """A* for one further task."""
    input:
        voxels=out("voxels/voxels.parquet"),
    output:
        out("tasks/{task}/waypoints.parquet"),
    params:
        slice=lambda w: params("plan", "plan", job_of(w)),
    log:
        out("logs/tasks/{task}_plan.log"),
    wildcard_constraints:
        task=TASK_RE,
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/plan.py"


rule verify_task:
    """Direct line and planned path of one further task, carrying its payload."""
    input:
        waypoints=out("tasks/{task}/waypoints.parquet"),
    output:
        timeseries=out("tasks/{task}/timeseries.parquet"),
        segments=out("tasks/{task}/segments.parquet"),
        csv=out("tasks/{task}/summary.csv"),
        md=out("tasks/{task}/summary.md"),
    params:
        slice=lambda w: params("verify", "verify", job_of(w)),
    log:
        out("logs/tasks/{task}_verify.log"),
    wildcard_constraints:
        task=TASK_RE,
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/verify.py"


rule verify_task_plots:
    """Workspace with both paths; loads against their limits (one further task)."""
    input:
        voxels=out("voxels/voxels.parquet"),
        configurations=out("voxels/configurations.parquet"),
        timeseries=out("tasks/{task}/timeseries.parquet"),
    output:
        workspace=report(out("tasks/{task}/workspace.png"), category="Verification", subcategory="task {task}",
                         caption="../report/workspace.rst"),
        torques=report(out("tasks/{task}/torques.png"), category="Verification", subcategory="task {task}",
                       caption="../report/loads.rst"),
        force=report(out("tasks/{task}/base_force.png"), category="Verification", subcategory="task {task}",
                     caption="../report/loads.rst"),
        moment=report(out("tasks/{task}/base_moment.png"), category="Verification", subcategory="task {task}",
                      caption="../report/loads.rst"),
    params:
        slice=lambda w: params("verify", "verify_plots", job_of(w)),
    log:
        out("logs/tasks/{task}_plots.log"),
    wildcard_constraints:
        task=TASK_RE,
    conda:
        "../envs/capmap.yaml"
    script:
        "../scripts/verify_plots.py"
