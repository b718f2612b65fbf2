# Method family 3: reconfigurable robot, one boom reconfigured in a closed chain (one job per method).
RECONFIG_METHODS = ["nullspace", "pinv"] if RUN.reconfig else []


rule reconfig:
    """Plan the boom reconfiguration: null-space singularity avoidance or the plain pseudo-inverse."""
    input:
        robot=lambda w: RUN.reconfig.robot,
    output:
        table=out("reconfig/{method}.parquet"),
        timing=out("reconfig/{method}_timing.json"),
    log:
        out("logs/reconfig/{method}.log"),
    wildcard_constraints:
        method="nullspace|pinv",
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda w: params(f"reconfig_{w.method}", "reconfig"),
    script:
        "../scripts/reconfig.py"


rule reconfig_summary:
    """Both methods side by side: m, closure, rates, range margins, time per step."""
    input:
        tables=expand(out("reconfig/{method}.parquet"), method=RECONFIG_METHODS),
        timings=expand(out("reconfig/{method}_timing.json"), method=RECONFIG_METHODS),
    output:
        csv=out("reconfig/summary.csv"),
        md=out("reconfig/summary.md"),
    log:
        out("logs/reconfig/summary.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        code=code_params("reconfig_summary"),
    script:
        "../scripts/reconfig_summary.py"


rule reconfig_plots:
    """m(t), joint rates and the passive joint's motion for both methods."""
    input:
        expand(out("reconfig/{method}.parquet"), method=RECONFIG_METHODS),
    output:
        manipulability=report(
            out("reconfig/manipulability.png"),
            category="Reconfiguration",
            caption="../report/reconfig_manipulability.rst",
        ),
        rates=report(
            out("reconfig/joint_rates.png"), category="Reconfiguration", caption="../report/reconfig_rates.rst"
        ),
        passive=report(
            out("reconfig/passive_joint.png"), category="Reconfiguration", caption="../report/reconfig_passive.rst"
        ),
    log:
        out("logs/reconfig/plots.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        code=code_params("reconfig_plots"),
    script:
        "../scripts/reconfig_plots.py"


rule reconfig_animation:
    """Offline 3D animation (MeshCat static HTML) of the reconfiguration."""
    input:
        robot=lambda w: RUN.reconfig.robot,
        tables=expand(out("reconfig/{method}.parquet"), method=RECONFIG_METHODS),
    output:
        report(out("reconfig/animation.html"), category="Reconfiguration", caption="../report/reconfig_animation.rst"),
    log:
        out("logs/reconfig/animation.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        slice=lambda w: params("reconfig_animation", "reconfig_animation"),
    script:
        "../scripts/reconfig_animation.py"
