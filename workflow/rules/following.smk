# Method family 2: torque-limited following vs TOPP-RA (one job per case).

def follow_inputs(wildcards):
    """space: the plan of its payload (the path it follows); ground: the robot file."""
    if wildcards.case == "space":
        m = payload_label(config["follow"]["space"]["payload_kg"])
        return {"waypoints": f"results/plan/payload_{m}kg/waypoints.parquet"}
    return {"robot": config["follow"]["ground"]["robot"]}


rule follow:
    """Torque-limited S-curve following, segment by segment, and TOPP-RA on the same path and limits."""
    input:
        unpack(follow_inputs),
    output:
        timeseries="results/follow/{case}/timeseries.parquet",
        toppra="results/follow/{case}/toppra.parquet",
        csv="results/follow/{case}/summary.csv",
        md="results/follow/{case}/summary.md",
    params:
        slice=lambda w: with_code(canonical(FOLLOW_SLICES[w.case]), "follow"),
    log:
        "results/logs/follow/{case}.log",
    wildcard_constraints:
        case="space|ground",
    script:
        "../scripts/follow.py"


rule follow_plots:
    """Command vs followed vs TOPP-RA path coordinate, lag, deviation; torques before and after limiting."""
    input:
        timeseries="results/follow/{case}/timeseries.parquet",
        toppra="results/follow/{case}/toppra.parquet",
    output:
        s=report("results/follow/{case}/progress.png", category="Following", subcategory="{case}",
                 caption="../report/follow_progress.rst"),
        torques=report("results/follow/{case}/torques.png", category="Following", subcategory="{case}",
                       caption="../report/follow_torques.rst"),
    params:
        slice=lambda w: with_code(canonical(FOLLOW_SLICES[w.case]), "follow_plots"),
    log:
        "results/logs/follow/plots_{case}.log",
    wildcard_constraints:
        case="space|ground",
    script:
        "../scripts/follow_plots.py"


rule follow_summary:
    """Follower vs TOPP-RA for every case."""
    input:
        expand("results/follow/{case}/summary.csv", case=FOLLOW_CASES),
    output:
        csv=report("results/follow/summary.csv", category="Following", caption="../report/follow_summary.rst"),
        md="results/follow/summary.md",
    params:
        code=with_code("{}", "follow_summary"),
    log:
        "results/logs/follow/summary.log",
    script:
        "../scripts/follow_summary.py"
