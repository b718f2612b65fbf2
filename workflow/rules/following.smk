# Method family 2: torque-limited following vs TOPP-RA (one job per case).


rule follow:
    """Torque-limited S-curve following, segment by segment, and TOPP-RA on the same path and limits."""
    input:
        unpack(follow_inputs),
    output:
        timeseries=out("follow/{case}/timeseries.parquet"),
        toppra=out("follow/{case}/toppra.parquet"),
        csv=out("follow/{case}/summary.csv"),
        md=out("follow/{case}/summary.md"),
    log:
        out("logs/follow/{case}.log"),
    wildcard_constraints:
        case="space|ground",
    priority: 10
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda w: params(f"follow_{w.case}", "follow", follow_job() if w.case == "space" else None),
    script:
        "../scripts/follow.py"


rule follow_plots:
    """The follower's duration against TOPP-RA's (path coordinate, speed, lag; the gap split into the command's and
    the torque limits' parts); torques before and after limiting; their split into link dynamics, rotor inertia and
    friction (a robot without drives: the follower's torques against TOPP-RA's)."""
    input:
        timeseries=out("follow/{case}/timeseries.parquet"),
        toppra=out("follow/{case}/toppra.parquet"),
    output:
        s=report(
            out("follow/{case}/progress.png"),
            category="Following",
            subcategory="{case}",
            caption="../report/follow_progress.rst",
        ),
        torques=report(
            out("follow/{case}/torques.png"),
            category="Following",
            subcategory="{case}",
            caption="../report/follow_torques.rst",
        ),
        split=report(
            out("follow/{case}/torque_split.png"),
            category="Following",
            subcategory="{case}",
            caption="../report/follow_torque_split.rst",
        ),
    log:
        out("logs/follow/plots_{case}.log"),
    wildcard_constraints:
        case="space|ground",
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda w: params(f"follow_{w.case}", "follow_plots", follow_job() if w.case == "space" else None),
    script:
        "../scripts/follow_plots.py"


rule follow_summary:
    """Follower vs TOPP-RA for every case."""
    input:
        expand(out("follow/{case}/summary.csv"), case=FOLLOW_CASES),
    output:
        csv=out("follow/summary.csv"),
        md=out("follow/summary.md"),
    log:
        out("logs/follow/summary.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        code=code_params("follow_summary"),
    script:
        "../scripts/follow_summary.py"
