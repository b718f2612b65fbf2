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
        slice=lambda w: slice_json("verify", w.payload),
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
        slice=lambda w: slice_json("verify", w.payload),
    log:
        "results/logs/verify/plots_payload_{payload}kg.log",
    wildcard_constraints:
        payload=PAYLOAD_RE,
    script:
        "../scripts/verify_plots.py"


rule verify_summary:
    """Every payload's verification in one table (in the report)."""
    input:
        expand("results/verify/payload_{payload}kg/summary.csv", payload=PAYLOADS),
    output:
        csv=report("results/verify/summary.csv", category="Verification", caption="../report/verify_summary.rst"),
        md="results/verify/summary.md",
    log:
        "results/logs/verify/summary.log",
    script:
        "../scripts/verify_summary.py"
