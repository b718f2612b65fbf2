# Method family 1: capacity map -> plan -> verify (one plan/verify job per payload).


rule model:
    """Load and validate the robot; write its joint/link table."""
    input:
        robot=config["robot"],
    output:
        "results/model/joints.parquet",
    params:
        slice=with_code(slice_json("model"), "model"),
    log:
        "results/logs/model.log",
    script:
        "../scripts/model.py"


rule sample:
    """Monte Carlo workspace of the locked arm (seeded)."""
    input:
        model="results/model/joints.parquet",
    output:
        "results/sample/points.parquet",
    params:
        slice=with_code(slice_json("sample"), "sample"),
    log:
        "results/logs/sample.log",
    script:
        "../scripts/sample.py"


rule capacity:
    """Shard k of n: every IK branch at the task orientation x every direction, per point."""
    input:
        points="results/sample/points.parquet",
    output:
        "results/capacity/shard_{k}_of_{n}.parquet",
    params:
        slice=with_code(slice_json("capacity"), "capacity"),
    log:
        "results/logs/capacity/shard_{k}_of_{n}.log",
    wildcard_constraints:
        k=r"\d+",
        n=r"\d+",
    script:
        "../scripts/capacity.py"


rule voxels:
    """Gather the shards into the voxel grid (minimum capacity over the sampled points per voxel)."""
    input:
        shards=expand("results/capacity/shard_{k}_of_{n}.parquet", k=range(SHARDS), n=SHARDS),
    output:
        voxels="results/voxels/sampled.parquet",
        points="results/voxels/points.parquet",
    params:
        slice=with_code(slice_json("voxels"), "voxels"),
    log:
        "results/logs/voxels.log",
    script:
        "../scripts/voxels.py"


rule refine:
    """Shard k of n of the reachable voxels: each voxel's minimum refined until it converges."""
    input:
        voxels="results/voxels/sampled.parquet",
    output:
        "results/voxels/refined_{k}_of_{n}.parquet",
    params:
        slice=with_code(slice_json("refine"), "refine"),
    log:
        "results/logs/refine/shard_{k}_of_{n}.log",
    wildcard_constraints:
        k=r"\d+",
        n=r"\d+",
    script:
        "../scripts/refine.py"


rule voxel_map:
    """The voxel map every later stage reads: the sampled voxels with their refined values."""
    input:
        sampled="results/voxels/sampled.parquet",
        refined=expand("results/voxels/refined_{k}_of_{n}.parquet", k=range(SHARDS), n=SHARDS) if REFINE else [],
    output:
        "results/voxels/voxels.parquet",
    params:
        slice=with_code(slice_json("refine"), "voxel_map"),
    log:
        "results/logs/voxel_map.log",
    script:
        "../scripts/voxel_map.py"


rule summary:
    """Capacity summary table and workspace figure (in the report)."""
    input:
        voxels="results/voxels/voxels.parquet",
        points="results/voxels/points.parquet",
    output:
        csv=report("results/summary/capacity_summary.csv", category="Capacity map", caption="../report/summary.rst"),
        md="results/summary/capacity_summary.md",
        png=report("results/summary/capacity_map.png", category="Capacity map", caption="../report/capacity_map.rst"),
    params:
        slice=with_code(slice_json("refine"), "summary"),
    log:
        "results/logs/summary.log",
    script:
        "../scripts/summary.py"


rule plan:
    """Improved A* through the voxels that carry the task payload (one job per payload)."""
    input:
        voxels="results/voxels/voxels.parquet",
    output:
        "results/plan/payload_{payload}kg/waypoints.parquet",
    params:
        slice=lambda w: with_code(slice_json("plan", w.payload), "plan"),
    log:
        "results/logs/plan/payload_{payload}kg.log",
    wildcard_constraints:
        payload=PAYLOAD_RE,
    script:
        "../scripts/plan.py"


rule verify:
    """Direct line and planned path: trapezoidal timing, continuous-branch IK, loads carrying the payload."""
    input:
        waypoints="results/plan/payload_{payload}kg/waypoints.parquet",
    output:
        timeseries="results/verify/payload_{payload}kg/timeseries.parquet",
        segments="results/verify/payload_{payload}kg/segments.parquet",
        csv="results/verify/payload_{payload}kg/summary.csv",
        md="results/verify/payload_{payload}kg/summary.md",
    params:
        slice=lambda w: with_code(slice_json("verify", w.payload), "verify"),
    log:
        "results/logs/verify/payload_{payload}kg.log",
    wildcard_constraints:
        payload=PAYLOAD_RE,
    script:
        "../scripts/verify.py"


rule verify_plots:
    """Capacity workspace with both paths; torques, base force and moment against their limits."""
    input:
        voxels="results/voxels/voxels.parquet",
        timeseries="results/verify/payload_{payload}kg/timeseries.parquet",
    output:
        workspace=report("results/verify/payload_{payload}kg/workspace.png", category="Verification",
                         subcategory="{payload} kg", caption="../report/workspace.rst"),
        torques=report("results/verify/payload_{payload}kg/torques.png", category="Verification",
                       subcategory="{payload} kg", caption="../report/loads.rst"),
        force=report("results/verify/payload_{payload}kg/base_force.png", category="Verification",
                     subcategory="{payload} kg", caption="../report/loads.rst"),
        moment=report("results/verify/payload_{payload}kg/base_moment.png", category="Verification",
                      subcategory="{payload} kg", caption="../report/loads.rst"),
    params:
        slice=lambda w: with_code(slice_json("verify", w.payload), "verify_plots"),
    log:
        "results/logs/verify/plots_payload_{payload}kg.log",
    wildcard_constraints:
        payload=PAYLOAD_RE,
    script:
        "../scripts/verify_plots.py"


rule verify_summary:
    """Every payload's and further task's verification in one table (in the report)."""
    input:
        expand("results/verify/payload_{payload}kg/summary.csv", payload=PAYLOADS),
        expand("results/tasks/{task}/summary.csv", task=TASKS),
    output:
        csv=report("results/verify/summary.csv", category="Verification", caption="../report/verify_summary.rst"),
        md="results/verify/summary.md",
    params:
        code=with_code("{}", "verify_summary"),
    log:
        "results/logs/verify/summary.log",
    script:
        "../scripts/verify_summary.py"


rule plan_gain:
    """Random tasks on this map planned with isotropic and direction-aware moves; gains verified."""
    input:
        voxels="results/voxels/voxels.parquet",
    output:
        tasks="results/plan/gain_tasks.parquet",
        csv=report("results/plan/gain.csv", category="Planning", caption="../report/gain.rst"),
        md="results/plan/gain.md",
    params:
        slice=with_code(slice_json("gain"), "plan_gain"),
    log:
        "results/logs/plan/gain.log",
    script:
        "../scripts/plan_gain.py"


# Further tasks (config `tasks`): the same plan, verify and plot stages on their own start, goal,
# payload and start configuration, one job each, under results/tasks/<name>/.


rule plan_task:
    """A* for one further task."""
    input:
        voxels="results/voxels/voxels.parquet",
    output:
        "results/tasks/{task}/waypoints.parquet",
    params:
        slice=lambda w: with_code(canonical(TASK_SLICES[w.task]["plan"]), "plan"),
    log:
        "results/logs/tasks/{task}_plan.log",
    wildcard_constraints:
        task=TASK_RE,
    script:
        "../scripts/plan.py"


rule verify_task:
    """Direct line and planned path of one further task, carrying its payload."""
    input:
        waypoints="results/tasks/{task}/waypoints.parquet",
    output:
        timeseries="results/tasks/{task}/timeseries.parquet",
        segments="results/tasks/{task}/segments.parquet",
        csv="results/tasks/{task}/summary.csv",
        md="results/tasks/{task}/summary.md",
    params:
        slice=lambda w: with_code(canonical(TASK_SLICES[w.task]["verify"]), "verify"),
    log:
        "results/logs/tasks/{task}_verify.log",
    wildcard_constraints:
        task=TASK_RE,
    script:
        "../scripts/verify.py"


rule verify_task_plots:
    """Workspace with both paths; loads against their limits (one further task)."""
    input:
        voxels="results/voxels/voxels.parquet",
        timeseries="results/tasks/{task}/timeseries.parquet",
    output:
        workspace=report("results/tasks/{task}/workspace.png", category="Verification", subcategory="task {task}",
                         caption="../report/workspace.rst"),
        torques=report("results/tasks/{task}/torques.png", category="Verification", subcategory="task {task}",
                       caption="../report/loads.rst"),
        force=report("results/tasks/{task}/base_force.png", category="Verification", subcategory="task {task}",
                     caption="../report/loads.rst"),
        moment=report("results/tasks/{task}/base_moment.png", category="Verification", subcategory="task {task}",
                      caption="../report/loads.rst"),
    params:
        slice=lambda w: with_code(canonical(TASK_SLICES[w.task]["verify"]), "verify_plots"),
    log:
        "results/logs/tasks/{task}_plots.log",
    wildcard_constraints:
        task=TASK_RE,
    script:
        "../scripts/verify_plots.py"
