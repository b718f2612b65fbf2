# The fault atlas: one coarse capacity map per (locked joint, lock angle), then the atlas table.
#   snakemake --cores 2 atlas
ATLAS_CASES = RUN.atlas.cases if RUN.atlas else []  # (joint, angle label)
ATLAS_DIRS = [out(f"atlas/joint{j}_angle{a}") for j, a in ATLAS_CASES]


rule atlas_map:
    """Capacity map with joint {joint} locked at {angle} deg, and its summary per task payload."""
    input:
        robot=RUN.robot,
    output:
        voxels=out("atlas/joint{joint}_angle{angle}/voxels.parquet"),
        summary=out("atlas/joint{joint}_angle{angle}/summary.parquet"),
    log:
        out("logs/atlas/joint{joint}_angle{angle}.log"),
    wildcard_constraints:
        joint=r"\d+",
        angle=r"-?\d+(\.\d+)?",
    conda:
        "../envs/capmap.yaml"
    params:
        slice=params("atlas_map", "atlas_map") if RUN.atlas else code_params("atlas_map"),
    script:
        "../scripts/atlas_map.py"


rule atlas_tables:
    """The atlas table, the capacity-volume curves and their figures."""
    input:
        summaries=[f"{d}/summary.parquet" for d in ATLAS_DIRS],
        voxels=[f"{d}/voxels.parquet" for d in ATLAS_DIRS],
    output:
        atlas=out("atlas/atlas.parquet"),
        curves=out("atlas/curves.parquet"),
        heatmap=report(out("atlas/heatmap.png"), category="Fault atlas", caption="../report/atlas_heatmap.rst"),
        curves_png=report(out("atlas/curves.png"), category="Fault atlas", caption="../report/atlas_curves.rst"),
    log:
        out("logs/atlas/atlas.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        slice=params("atlas", "atlas") if RUN.atlas else code_params("atlas"),
    script:
        "../scripts/atlas.py"


rule atlas_catalogue:
    """Catalogue of the atlas datasets."""
    input:
        [f"{d}/{name}.parquet" for d in ATLAS_DIRS for name in ("voxels", "summary")],
        out("atlas/atlas.parquet"),
        out("atlas/curves.parquet"),
    output:
        out("atlas/catalogue.parquet"),
    log:
        out("logs/atlas/catalogue.log"),
    conda:
        "../envs/capmap.yaml"
    params:
        code=code_params("catalogue"),
    script:
        "../scripts/catalogue.py"


rule atlas:
    """Target: the fault atlas of the config's atlas section."""
    input:
        out("atlas/atlas.parquet"),
        out("atlas/heatmap.png"),
        out("atlas/curves.png"),
        out("atlas/catalogue.parquet"),
