# Where to brake a failing joint, and what survives any one failure (not part of `all`):
#   snakemake --cores 2 advise        (capmap advise --joint J: one joint's advice)


rule lock_sweep:
    """The maps of the arm with joint {joint} locked at every angle of its sweep, on one grid."""
    input:
        robot=RUN.robot,
    output:
        out("advice/sweeps/joint{joint}.parquet"),
    log:
        out("logs/advice/sweep_joint{joint}.log"),
    wildcard_constraints:
        joint=r"\d+",
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda wc: advice_params("lock_sweep"),
        stands_at=stands_at,
    script:
        "../scripts/lock_sweep.py"


rule advice_tasks:
    """The run's tasks verified at every angle of joint {joint}'s sweep (and the run's own plans there)."""
    input:
        sweep=out("advice/sweeps/joint{joint}.parquet"),
        plans=[out(f"{d}/waypoints.parquet") for d in PLAN_DIRS],
    output:
        tasks=out("advice/joint{joint}/tasks.parquet"),
        healthy=out("advice/joint{joint}/healthy.parquet"),
    log:
        out("logs/advice/tasks_joint{joint}.log"),
    wildcard_constraints:
        joint=r"\d+",
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda wc: advice_params("advice_tasks"),
    script:
        "../scripts/advice_tasks.py"


rule advice_joint:
    """Where to brake joint {joint}: the recommendation, its convergence with the step, the margins' figure."""
    input:
        tasks=out("advice/joint{joint}/tasks.parquet"),
        healthy=out("advice/joint{joint}/healthy.parquet"),
    output:
        advice=out("advice/joint{joint}/advice.parquet"),
        convergence=out("advice/joint{joint}/convergence.parquet"),
        figure=report(out("advice/joint{joint}/margins.png"), category="Lock-angle advice"),
    log:
        out("logs/advice/advice_joint{joint}.log"),
    wildcard_constraints:
        joint=r"\d+",
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda wc: advice_params("advice"),
    script:
        "../scripts/advice.py"


rule tolerant:
    """The failure-tolerant map: the least capacity over every joint's sweep, beside the healthy arm's."""
    input:
        sweeps=expand(out("advice/sweeps/joint{joint}.parquet"), joint=range(1, N_JOINTS + 1)),
    output:
        tolerant=out("advice/tolerant.parquet"),
        summary=out("advice/tolerant_summary.parquet"),
        figure=report(out("advice/tolerant.png"), category="Lock-angle advice"),
    log:
        out("logs/advice/tolerant.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda wc: advice_params("tolerant"),
    script:
        "../scripts/tolerant.py"


ADVICE_DATASETS = [
    *expand(out("advice/sweeps/joint{joint}.parquet"), joint=range(1, N_JOINTS + 1)),
    *[
        out(f"advice/joint{j}/{name}.parquet")
        for j in ADVICE_JOINTS
        for name in ("tasks", "healthy", "advice", "convergence")
    ],
    out("advice/tolerant.parquet"),
    out("advice/tolerant_summary.parquet"),
]


rule advice_catalogue:
    """Catalogue of the advice's datasets."""
    input:
        ADVICE_DATASETS,
    output:
        out("advice/catalogue.parquet"),
    log:
        out("logs/advice/catalogue.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        code=code_params("catalogue"),
    script:
        "../scripts/catalogue.py"


rule advise:
    """Target: the advice for every joint of advice.joints and the failure-tolerant map."""
    input:
        [out(f"advice/joint{j}/margins.png") for j in ADVICE_JOINTS],
        out("advice/tolerant.png"),
        out("advice/catalogue.parquet"),
